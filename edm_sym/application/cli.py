"""Command line: ``edm`` and ``edm-export`` (docs/cli.md).

Exit status: 0 done; 1 the work itself failed; 2 bad input or usage. Bad input
prints one line naming the file and field, row or column, with what was
expected and what was found; no traceback reaches the user (set EDM_DEBUG=1 to
see one).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import traceback
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from edm_sym.core.errors import (
    TOO_DEEP,
    DataFormatError,
    EdmError,
    ExternalToolError,
    ToolMissingError,
    as_options,
    where_as_options,
)
from edm_sym.core.fileio import check_outputs


class UsageError(EdmError):
    """Bad command-line usage (exit 2)."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line, exit 2: docs/cli.md#exit-status
        raise UsageError(f"{self.prog}: {message}")


def _shown(text: str) -> str:
    """An option's value for a message: quoted, and cut when it is very long."""
    return repr(text) if len(text) <= 40 else f"{text[:20]!r}... ({len(text)} characters)"


def _finite_float(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, found {_shown(text)}") from None
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"expected a finite number, found {_shown(text)}")
    return v


def _positive_float(text: str) -> float:
    v = _finite_float(text)
    if not v > 0:
        raise argparse.ArgumentTypeError(f"expected a positive number, found {_shown(text)}")
    return v


def _seed(text: str) -> int:
    """A random seed: an integer in [0, 2**32), which numpy's generators take."""
    if not (text.isascii() and text.isdigit() and len(text) <= 10 and int(text) < 2**32):
        raise argparse.ArgumentTypeError(f"expected an integer >= 0 and < {2**32}, found {_shown(text)}")
    return int(text)


#: Help of every DATA argument.
DATA_HELP = "a log: CSV, .npz, .mat, or plant:PRESET/EXCITATION[@SEED] (docs/cli.md#data-files)"
#: Help of every --ts option.
TS_HELP = "sample time [s] of a log without a 't' column"
#: The roles a --role option takes (edm_sym.core.data.LOG_ROLES).
ROLES_HELP = "time, target, position, position_wrapped, velocity, acceleration or input"


#: The options several subcommands take, defined once: flags, type, choices, metavar and
#: default. Each subcommand says in its help what the option means there.
_SHARED_OPTIONS: dict[str, tuple[tuple[str, ...], dict[str, Any]]] = {
    "--ts": (("--ts",), {"type": _positive_float, "metavar": "SECONDS"}),
    "--seed": (("--seed",), {"type": _seed, "default": 0, "metavar": "N"}),
    "--axis": (("--axis",), {"choices": ["rotary", "linear"]}),
    "-o": (("-o", "--output"), {}),
}


def _add_shared(p: argparse.ArgumentParser, option: str, text: str, **settings: Any) -> None:
    """Add one of :data:`_SHARED_OPTIONS` to subcommand ``p``, with its help ``text`` there.

    ``settings`` are a subcommand's own argparse settings over the shared ones
    (``-o``'s metavar and default; ``flags`` replaces the option's flags).
    """
    flags, shared = _SHARED_OPTIONS[option]
    p.add_argument(*settings.pop("flags", flags), **{**shared, **settings}, help=text)


def _add_column_args(p: argparse.ArgumentParser, *, roles: bool = True, axis: bool = True) -> None:
    """``--time-column``, ``--role`` and ``--axis`` of a command that reads a log (docs/data.md)."""
    p.add_argument("--time-column", metavar="COL",
                   help="the log's time column [s] (default: t, or the one the model records)")
    p.add_argument("--columns", metavar="NAME[,NAME...]",
                   help="the names of the columns of a matrix selected as FILE.mat:VAR (or .h5, "
                        ".npz), in its column order (docs/data.md#files-loggers-write)")
    if roles:
        p.add_argument("--role", action="append", default=[], metavar="COL=ROLE",
                       help=f"what a column is: {ROLES_HELP} (repeatable; docs/data.md"
                            "#columns-and-roles)")
    if axis:
        _add_shared(p, "--axis", "the axis, which sets the SI units: rotary (rad, N m) or linear "
                               "(m, N) (default: the model's, else rotary)")


def _columns(args: argparse.Namespace):  # noqa: ANN202
    """The column roles the options give (a ColumnRoles; empty without options)."""
    from edm_sym.core.data import ColumnRoles

    return ColumnRoles.parse(getattr(args, "role", None) or (), time_column=args.time_column,
                             where="--role")


def _add_version(parser: argparse.ArgumentParser) -> None:
    from edm_sym.core.version import __version__

    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")


def _add_export_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("result", metavar="RESULT.json", help="result file to export")
    p.add_argument("--target", required=True, choices=["c", "python", "latex", "test", "all"],
                   help="C header and source, a Python module, the LaTeX report, the C "
                        "verification kit (test), or all of c, python and latex")
    _add_shared(p, "-o", "output folder (default: generated/<folder holding RESULT>/)",
                flags=("-o", "--out-dir"), metavar="DIR")
    p.add_argument("--prefix", default="edm_comp", help="file and symbol prefix (default edm_comp)")
    p.add_argument("--real", default="double", choices=["float", "double", "q31", "q15"],
                   help="the C real type, or an integer-only fixed-point build (default double)")
    p.add_argument("--input-range", action="append", type=_input_range, metavar="NAME=LO:HI",
                   help="an input's range for a fixed-point build or the kit, over the one the "
                        "result records (repeatable)")
    p.add_argument("--pdf", action="store_true", help="compile the LaTeX report with latexmk")
    p.add_argument("--data", metavar="DATA", nargs="+",
                   help="abstraction log(s), for the report (figures per log, the fit per log "
                        "and over all) and the summary")
    p.add_argument("--eval-data", metavar="DATA", nargs="+",
                   help="evaluation log(s), for the report and the summary, as --data")
    p.add_argument("--lugre", metavar="LUGRE.json", help="LuGre result, for the report's comparison")
    _add_shared(p, "--ts", "sample time of logs without a 't' column")
    p.add_argument("--front-member", type=int, metavar="K",
                   help="export member K (1-based) of the result's parsimony front instead of "
                        "the selected one")
    _add_shared(p, "--axis", "the units of the outputs: rotary (rad, N m) or linear (m, N) "
                             "(default: the result's axis)")
    p.set_defaults(func=_cmd_export)


def _input_range(text: str) -> tuple[str, tuple[float, float]]:
    name, sep, span = text.partition("=")
    lo, colon, hi = span.rpartition(":")
    try:
        pair = (float(lo), float(hi))
    except ValueError:
        pair = None
    if not (sep and colon and name and pair and pair[0] <= pair[1]):
        raise argparse.ArgumentTypeError(f"expected NAME=LO:HI with LO <= HI, found {text!r}")
    return name, pair


def _percent(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a percentage, found {text!r}") from None
    if not 0 <= v < 100:
        raise argparse.ArgumentTypeError(f"expected a percentage in [0, 100), found {text}")
    return v


def _add_describe_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("result", metavar="RESULT.json", help="result file to describe")
    p.add_argument("--data", metavar="DATA", nargs="+",
                   help="log to measure the contributions on (default: the evaluation, else the "
                        "abstraction log the result records); several: described one by one")
    p.add_argument("--json", action="store_true", help="print the stable JSON of docs/describe.md")
    p.add_argument("--threshold", type=_percent, default=1.0, metavar="PCT",
                   help="a row below this share of the target's RMS is negligible (default 1)")
    _add_shared(p, "--ts", "sample time of a log without a 't' column")
    p.add_argument("--resample", action="store_true",
                   help="resample a log whose sample time differs from the result's by more than "
                        "0.1 %% onto its grid (default: refuse it)")
    p.add_argument("--observer-bandwidth", type=_positive_float, metavar="RAD_PER_S",
                   help="bandwidth g of the observer that estimated the target, g/(s+g), to name "
                        "the inertia the rows hold with its lag taken out (default: the one "
                        "edm abstract was told, else the log's scalar observer_bandwidth; "
                        "plant: logs record it)")
    _add_column_args(p, roles=False)
    p.set_defaults(func=_cmd_describe)


def _cmd_describe(args: argparse.Namespace) -> int:
    from edm_sym.engines.description import describe
    from edm_sym.engines.symbolic.significance import SignificanceOptions

    specs = list(args.data) if args.data else [None]
    if args.columns is not None:
        # A matrix of a .mat file named by --columns: read here, with the roles the result records.
        from edm_sym.core.result import load_result
        from edm_sym.engines.sources import load_data

        result = load_result(args.result)
        roles = _columns(args).over(result.column_roles())
        specs = [load_data(spec, ts=args.ts, require=[*result.inputs, result.target],
                           default_ts=result.sample_time, columns=roles, names=args.columns)
                 for spec in specs if spec is not None]
    descs = []
    for spec in specs:  # several logs: each described on its own, from rest
        descs.append(describe(args.result, data=spec, ts=args.ts,
                              options=SignificanceOptions(threshold=args.threshold / 100),
                              axis=args.axis, columns=_columns(args), resample=args.resample,
                              observer_bandwidth=args.observer_bandwidth))
    if len(descs) == 1:
        print(json.dumps(descs[0].to_json(), indent=2, allow_nan=False) if args.json
              else descs[0].table())
        return 0
    names = [getattr(spec, "source", None) or str(spec) for spec in specs]
    if args.json:
        print(json.dumps({"logs": [{"data": name, **d.to_json()} for name, d in zip(names, descs,
                                                                                   strict=True)]},
                         indent=2, allow_nan=False))
        return 0
    for k, (name, d) in enumerate(zip(names, descs, strict=True)):
        print(("\n" if k else "") + f"== {name} ({k + 1} of {len(descs)}) ==")
        print(d.table())
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The ``edm`` argument parser with all its subcommands."""
    parser = _Parser(prog="edm", description="Element Description Method compensators for "
                     "reaction torque observers: abstract, simulate, export.",
                     epilog="examples:\n"
                            "  edm plant --preset auger --excitation abstraction -o abs.csv\n"
                            "  edm abstract abs.csv --target tau_ext --inputs theta_w,omega,alpha -o r.json\n"
                            "  edm describe r.json\n"
                            "  edm-export r.json --target c\n"
                            "docs: docs/cli.md",
                     formatter_class=argparse.RawDescriptionHelpFormatter)
    _add_version(parser)
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    # One line per subcommand, in the order of `edm --help`; each adds its own options.
    _add_export_args(sub.add_parser("export", help="render a result as C, Python or LaTeX"))
    _add_abstract_args(sub.add_parser(
        "abstract", help="run the hierarchical EDM abstraction (GA) on a log"))
    _add_describe_args(sub.add_parser(
        "describe", help="what a result's model found: rows, physical terms, contributions, flags"))
    _add_simulate_args(sub.add_parser(
        "simulate", help="run the reference simulator of a model on a log"))
    _add_plant_args(sub.add_parser("plant", help="simulate a servo axis with RTOB in free motion"))
    _add_pipeline_args(sub.add_parser(
        "pipeline", help="data -> LuGre -> EDM -> evaluation -> export, from a TOML file"))
    _add_observe_args(sub.add_parser(
        "observe", help="build the reaction-torque-observer view of a measured log"))
    _add_lugre_args(sub.add_parser(
        "lugre", help="identify the LuGre baseline model on one or more logs"))
    _add_doctor_args(sub.add_parser(
        "doctor", help="list the optional tools (compilers, QEMU, LaTeX) and numba (the GA's row "
                       "kernel) found or missing"))
    return parser


def _add_abstract_args(p: argparse.ArgumentParser) -> None:
    """``edm abstract``: the log(s), columns, config, search and held-out options."""
    p.add_argument("data", metavar="DATA", nargs="*",
                   help=DATA_HELP + "; several logs are fitted together, each from rest (default: "
                        "the config's data list)")
    p.add_argument("--target", metavar="COL",
                   help="the column the compensator reproduces (the observer's torque estimate; "
                        "or --role COL=target)")
    p.add_argument("--inputs", metavar="COL[,COL...]",
                   help="the columns a row may take as its input, e.g. theta_w,omega,alpha "
                        "(default: the columns given an input role with --role or [columns])")
    p.add_argument("--config", metavar="FILE.toml",
                   help="the schedule and GA settings (default: the default schedule, docs/abstraction.md)")
    _add_shared(p, "--seed", "random seed; the same seed gives the same result.json (default 0)")
    p.add_argument("--time-limit", type=_positive_float, metavar="SECONDS",
                   help="end the search at this wall time and write the best so far (default: none, "
                        "the config's generation budget)")
    _add_shared(p, "-o", "the result file (default result.json; a checkpoint is kept beside it)",
                default="result.json", metavar="RESULT.json")
    _add_shared(p, "--ts", TS_HELP)
    p.add_argument("--resume", action="store_true", help="continue from the checkpoint")
    p.add_argument("--quiet", action="store_true",
                   help="no progress (bar on a terminal, a line every few seconds elsewhere)")
    p.add_argument("--workers", type=int, default=None, help="processes (default: all cores)")
    p.add_argument("--searches", type=int, default=None, metavar="K",
                   help="independent searches from seeds drawn from --seed, side by side on the "
                        "workers; the model is chosen among all their step bests (default: the "
                        "config's searches, 1)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="a dask scheduler (tcp://host:8786): evaluate on its workers instead "
                        "(needs edm_sym[dask]; docs/abstraction.md)")
    p.add_argument("--validation-share", type=float, metavar="SHARE",
                   help="share of DATA held out, 0-0.9, in the config's layout (default: "
                        "the config's, 0.2 in 10 blocks spread over the log)")
    p.add_argument("--validate", metavar="FILE",
                   help="a second log held out as a whole (the GA fits all of DATA)")
    p.add_argument("--select", metavar="RULE",
                   help="exported member of the pruned front: best, knee or simplest-within=PCT "
                        "(default: simplest-within=<tolerance>, 1 %%)")
    p.add_argument("--prune-tolerance", type=float, metavar="REL",
                   help="relative worsening a simplification may cost (default 0.01)")
    p.add_argument("--no-prune", action="store_true",
                   help="export the search's model as it is (no pruning, no front)")
    p.add_argument("--initial", metavar="PREVIOUS.json",
                   help="start the hierarchy from a previous result's rows (same axis, inputs and "
                        "sample time; docs/abstraction.md#a-model-that-carries-over)")
    p.add_argument("--decimate", type=int, metavar="K",
                   help="keep every K-th sample of each log after an anti-alias filter; the model "
                        "then runs at K times the log's sample time (docs/data.md#decimation)")
    p.add_argument("--decimate-to", type=_positive_float, metavar="SECONDS",
                   help="decimate each log to this sample time, a whole multiple of the log's "
                        "(K chosen per log; docs/data.md#decimation)")
    p.add_argument("--observer-bandwidth", type=_positive_float, metavar="RAD_PER_S",
                   help="bandwidth g of the observer that estimated the target, g/(s+g): the "
                        "static laws' block and the rows of linear laws are offered through its "
                        "low-pass before pruning (default: the log's scalar observer_bandwidth; "
                        "plant: logs record it)")
    _add_column_args(p)
    p.set_defaults(func=_cmd_abstract)


def _add_simulate_args(p: argparse.ArgumentParser) -> None:
    """``edm simulate``: a model and the logs to run it on."""
    p.add_argument("model", metavar="MODEL.json", help="an EDM result or a LuGre result")
    p.add_argument("data", metavar="DATA", nargs="+",
                   help=DATA_HELP + "; several logs are each simulated from rest")
    _add_shared(p, "-o", "output CSV (default: <DATA stem>_sim.csv in the current folder; with "
                         "several logs a folder for them)", metavar="OUT.csv")
    _add_shared(p, "--ts", "sample time [s] of a log without a 't' column (default: the model's)")
    p.add_argument("--resample", action="store_true",
                   help="resample a log whose sample time differs from the model's by more than "
                        "0.1 %% onto the model's grid (default: refuse it)")
    _add_column_args(p, roles=False)
    p.set_defaults(func=_cmd_simulate)


def _add_plant_args(p: argparse.ArgumentParser) -> None:
    """``edm plant``: the simulated servo axis and its excitation."""
    p.add_argument("--preset", required=True, metavar="NAME",
                   help="the plant: a preset of docs/plant.md (auger, ballscrew, lugre, ...) or "
                        "family-N, draw N of the family of plants with known truth")
    p.add_argument("--excitation", required=True, choices=["abstraction", "evaluation"],
                   help="velocity steps then the chirp of eq. 9 (abstraction), or eq. 17 (evaluation)")
    _add_shared(p, "-o", "output CSV (default: <preset>_<excitation>.csv)", metavar="DATA.csv")
    _add_shared(p, "--seed", "noise seed (default 0)")
    p.set_defaults(func=_cmd_plant)


def _add_pipeline_args(p: argparse.ArgumentParser) -> None:
    """``edm pipeline``: the pipeline file."""
    p.add_argument("pipeline", metavar="PIPELINE.toml", help="the pipeline file (docs/cli.md#edm-pipeline)")
    p.add_argument("--quiet", action="store_true",
                   help="no progress (bar on a terminal, a line every few seconds elsewhere)")
    p.add_argument("--reuse", action="store_true",
                   help="keep an existing lugre.json / result.json (evaluate and export only)")
    _add_shared(p, "--axis", "the axis, over the file's [data] axis (default: the file's, else rotary)")
    p.set_defaults(func=_cmd_pipeline)


def _add_observe_args(p: argparse.ArgumentParser) -> None:
    """``edm observe``: a measured log and the observer's settings."""
    p.add_argument("data", metavar="DATA", help=DATA_HELP)
    p.add_argument("--position", metavar="COL",
                   help="the measured position column (or --role COL=position)")
    p.add_argument("--force", required=True, metavar="COL",
                   help="the force (torque) command column, or a controller output to scale")
    p.add_argument("--force-gain", default="1", metavar="NUM|NAME",
                   help="number, or name of a scalar stored in DATA (e.g. gtau)")
    p.add_argument("--nominal-inertia", required=True, type=_finite_float, metavar="M_N",
                   help="the nominal mass or inertia the observer subtracts times the acceleration")
    p.add_argument("--cutoff", type=_positive_float, default=100.0, metavar="HZ",
                   help="corner of the zero-phase filter on the position (default 100 Hz)")
    _add_shared(p, "-o", "output CSV (default observer.csv)", default="observer.csv",
                metavar="OUT.csv")
    _add_shared(p, "--ts", TS_HELP)
    _add_column_args(p)
    p.set_defaults(func=_cmd_observe)


def _add_lugre_args(p: argparse.ArgumentParser) -> None:
    """``edm lugre``: the logs and the identification's settings."""
    p.add_argument("data", metavar="DATA", nargs="+",
                   help=DATA_HELP + "; several logs are each simulated from rest and fitted together")
    p.add_argument("--target", metavar="COL",
                   help="the torque column the model fits (or --role COL=target)")
    p.add_argument("--velocity", metavar="COL", help="the velocity column (or --role COL=velocity)")
    _add_shared(p, "--seed", "random seed of the global stage (default 0)")
    p.add_argument("--time-limit", type=_positive_float, metavar="SECONDS",
                   help="end the identification at this wall time (default: none)")
    p.add_argument("--method", default="scipy", choices=["scipy", "ga", "both"],
                   help="scipy's global + local search, the project's GA, or both compared "
                        "(default scipy; docs/lugre.md)")
    _add_shared(p, "-o", "the LuGre file (default lugre.json)", default="lugre.json",
                metavar="LUGRE.json")
    p.add_argument("--quiet", action="store_true",
                   help="no progress (bar on a terminal, a line every few seconds elsewhere)")
    _add_shared(p, "--ts", TS_HELP)
    _add_column_args(p)
    p.set_defaults(func=_cmd_lugre)


def _add_doctor_args(p: argparse.ArgumentParser) -> None:
    """``edm doctor``: a table, or JSON with ``--json``."""
    p.add_argument("--json", action="store_true",
                   help="print a JSON list of {kind, name, apt, purpose, found, location, version, "
                        "pip, status} instead")
    p.set_defaults(func=_cmd_doctor)


def _cmd_doctor(args: argparse.Namespace) -> int:
    from dataclasses import asdict

    from edm_sym.application.doctor import checks, report

    found = checks()
    if args.json:
        print(json.dumps([dict(asdict(c), found=c.found) for c in found], indent=2, sort_keys=True))
    else:
        print(report(found))
    return 0


def _cmd_export(args: argparse.Namespace) -> int:
    from edm_sym.core.result import load_result

    result = load_result(args.result)
    if args.axis is not None:
        from dataclasses import replace

        result = replace(result, axis=args.axis)
    if args.front_member is not None:
        from edm_sym.core.result import front_member

        result = front_member(result, args.front_member)
    from edm_sym.application.exporting import export_files
    out = Path(args.out_dir) if args.out_dir else Path("generated") / Path(args.result).resolve().parent.name
    inputs = [args.result, *(args.data or []), *(args.eval_data or []), args.lugre]
    check_outputs([out / name for name in _export_names(args)], [i for i in inputs if i],
                  option="-o" if args.out_dir else "output folder")
    # The summary's log is read (and refused) before any file is written.
    log = _summary_log(result, args)
    # The report draws every log and gives the fit on each and over all; the summary
    # judges all of them.
    written = export_files(result, args.target, out, prefix=args.prefix, real=args.real,
                           pdf=args.pdf, data=_one_or_all(args.data),
                           eval_data=_one_or_all(args.eval_data), lugre=args.lugre, ts=args.ts,
                           input_range=dict(args.input_range or ()))
    for path in written.files:
        print(path)
    for line in written.notes:
        print(line)
    _export_summary(result, args, log)
    return 0


def _one_or_all(specs: list[str] | None) -> str | list[str] | None:
    """A report option's logs: None, the one log, or the list of several."""
    return None if not specs else specs[0] if len(specs) == 1 else list(specs)


def _summary_log(result, args: argparse.Namespace):  # noqa: ANN001, ANN202
    """The log(s) the export's summary judges the result on (``--eval-data``, else ``--data``):
    one DataLog, a list of several, or None."""
    from edm_sym.engines.sources import load_data

    specs = args.eval_data or args.data
    if not specs:
        return None
    logs = [load_data(spec, ts=args.ts, require=[*result.inputs, result.target]) for spec in specs]
    return logs[0] if len(logs) == 1 else logs


def _export_summary(result, args: argparse.Namespace, log=None) -> None:  # noqa: ANN001
    """The closing summary of an export: the fitness the result records, and its flags."""
    from edm_sym.application.summary import NOT_MEASURED, fitness_line, print_summary, result_flags

    prog = "edm-export" if not hasattr(args, "command") else "edm export"
    notes = [fitness_line(result)] + ([] if log is not None else [NOT_MEASURED])
    if isinstance(log, list):
        notes += _rmse_lines(result, log)
    print_summary(prog, fitness=notes, flags=result_flags(result, log), describe=args.result)


def _rmse_lines(result, logs: list) -> list[str]:  # noqa: ANN001
    """The model's plain RMSE on each log (each simulated from rest) and over all of them."""
    import numpy as np

    from edm_sym.core.fitness import rms
    from edm_sym.core.units import axis_units
    from edm_sym.engines.simulate import simulate

    unit = axis_units(getattr(result, "axis", None) or "rotary").force
    errors = [log.column(result.target) - simulate(result, log).total for log in logs]
    lines = [f"rmse {rms(e):.6g} {unit} on {log.source}" for log, e in zip(logs, errors, strict=True)]
    return [*lines, f"rmse {rms(np.concatenate(errors)):.6g} {unit} over all {len(logs)} logs"]


def _export_names(args: argparse.Namespace) -> list[str]:
    """The files an export writes into its folder (the report's figures aside)."""
    names = {"c": [f"{args.prefix}.h", f"{args.prefix}.c"], "python": [f"{args.prefix}.py"],
             "latex": [f"{args.prefix}_report.tex"] + ([f"{args.prefix}_report.pdf"] if args.pdf else []),
             "test": [f"{args.prefix}_test.c"]}
    targets = ["c", "python", "latex"] if args.target == "all" else [args.target]
    return [n for t in targets for n in names[t]]


def _cmd_simulate(args: argparse.Namespace) -> int:
    from edm_sym.core.data import write_csv
    from edm_sym.core.fitness import rms
    from edm_sym.core.units import axis_units
    from edm_sym.engines.models import load_model
    from edm_sym.engines.sources import load_data

    model_path = Path(args.model)
    specs = list(args.data)
    if len(specs) == 1:
        outs = [Path(args.output) if args.output is not None else _sim_name(specs[0])]
    else:
        folder = Path(args.output) if args.output is not None else Path(".")
        if not folder.is_dir():
            raise UsageError(f"edm simulate: -o: expected a folder for the {len(specs)} logs' "
                             f"outputs, found {folder}")
        outs = [folder / _sim_name(spec) for spec in specs]
        if len(set(outs)) < len(outs):
            raise UsageError("edm simulate: DATA: expected logs of distinct names (each writes "
                             "<stem>_sim.csv), found two of one name")
    check_outputs(outs, [args.model, *specs])
    given = _columns(args)
    # The model is validated completely before the data is read.
    model = load_model(model_path)
    target = model.target
    if args.axis is not None and model.axis is not None and args.axis != model.axis:
        raise UsageError(f"edm simulate: --axis: expected {model.axis} as in {model_path.name}, "
                         f"found {args.axis}")
    axis = model.axis or args.axis or "rotary"
    # The time column and roles the model records, under those given now; every log is
    # read (and refused) before any file is written.
    logs = [_match_ts(model_path.name, model.sample_time,
                      load_data(spec, ts=args.ts, require=model.inputs, default_ts=model.sample_time,
                                columns=given.over(model.column_roles()), names=args.columns),
                      args.resample) for spec in specs]
    unit = axis_units(axis).force
    residuals = []
    for data, out in zip(logs, outs, strict=True):
        for line in model.beyond_ranges(data):
            print(line, file=sys.stderr)
        run = model.run(data)  # each log from rest
        cols = {_time_name(data): data.times, **run.parts, "tau_cmp": run.torque}
        rmse = None
        if target in data.columns:
            cols["residual"] = data.columns[target] - cols["tau_cmp"]
            rmse = rms(cols["residual"])
            residuals.append(cols["residual"])
        write_csv(out, cols)
        print(f"wrote {out}")
        where = f" ({data.source})" if len(logs) > 1 else ""
        print(f"rmse {rmse:.10g} {unit}{where}" if rmse is not None
              else f"rmse nan (no column {target!r} in {data.source if len(logs) > 1 else 'DATA'})")
    if len(logs) > 1 and residuals:
        import numpy as np

        print(f"rmse {rms(np.concatenate(residuals)):.10g} {unit} (over all {len(residuals)} logs "
              f"with the target, by their samples)")
    return 0


def _sim_name(spec: str) -> Path:
    """``<DATA stem>_sim.csv`` (a selection ``FILE.mat:VAR`` named by its file)."""
    from edm_sym.core.formats import split_spec

    return Path(f"{split_spec(spec)[0].stem}_sim.csv")


def _match_ts(name: str, ts: float, data, resample: bool):  # noqa: ANN001, ANN202
    """The log on the model's sample time (docs/data.md, "Sample time"); says what it assumed."""
    from edm_sym.core.data import drift, match_sample_time

    out = match_sample_time(data, ts, model=name, resample=resample)
    if out is not data:
        print(f"resampled {data.source} from {data.ts:.9g} s to {ts:.9g} s", file=sys.stderr)
    elif drift(data.ts, ts):
        print(f"sample time: {data.ts:.9g} s in {data.source}, {ts:.9g} s in {name} "
              f"(relative drift {drift(data.ts, ts):.2g}, accepted)", file=sys.stderr)
    return out


def _time_name(data) -> str:  # noqa: ANN001
    """The name of the output's first column: the log's time column, else ``t``."""
    return data.time_column or "t"


def _cmd_plant(args: argparse.Namespace) -> int:
    from edm_sym.core.data import write_csv
    from edm_sym.engines.plant import PRESETS, simulate_plant
    from edm_sym.engines.plant.family import FAMILY_PREFIX, family_draw, resolve_preset

    if args.preset not in PRESETS and family_draw(args.preset) is None:
        raise UsageError(f"edm plant: --preset: expected one of {', '.join(sorted(PRESETS))} "
                         f"or {FAMILY_PREFIX}N (a draw of the family), found {args.preset!r}")
    out = Path(args.output) if args.output else Path(f"{args.preset}_{args.excitation}.csv")
    check_outputs([out])
    log = simulate_plant(resolve_preset(args.preset), args.excitation, seed=args.seed)
    write_csv(out, log.columns)
    print(f"wrote {out}")
    return 0


def _cmd_pipeline(args: argparse.Namespace) -> int:
    from edm_sym.application.pipeline import run_pipeline

    run_pipeline(args.pipeline, progress=not args.quiet, reuse=args.reuse, axis=args.axis)
    return 0


def _cmd_observe(args: argparse.Namespace) -> int:
    from edm_sym.core.data import write_csv
    from edm_sym.core.units import axis_units
    from edm_sym.engines.observer import ObserverOptions, observer_view
    from edm_sym.engines.sources import load_data

    try:
        gain: float | str = float(args.force_gain)
    except ValueError:
        gain = args.force_gain
    given = _columns(args)
    position = _option_or_role(args.position, given, "position", "--position", "edm observe")
    try:
        opts = ObserverOptions(position, args.force, args.nominal_inertia, gain, args.cutoff)
    except ValueError as exc:  # named by the option that gave the value, not the field
        field, _, problem = str(exc).partition(": ")
        option = {"nominal_inertia": "--nominal-inertia", "cutoff_hz": "--cutoff",
                  "force_gain": "--force-gain"}.get(field, field)
        raise UsageError(f"edm observe: {option}: {problem}") from None
    check_outputs([args.output], [args.data])
    view = observer_view(load_data(args.data, ts=args.ts, columns=given, names=args.columns), opts)
    write_csv(args.output, view.columns)
    u = axis_units(args.axis or "rotary")
    print(f"wrote {args.output}")
    print(f"columns: q [{u.position}], qd [{u.velocity}], qdd [{u.acceleration}], force and "
          f"tau_ext [{u.force}] ({u.axis} axis); tau_ext = force - {args.nominal_inertia:g} "
          f"{u.inertia} * qdd")
    return 0


def _option_or_role(value: str | None, given, role: str, option: str,  # noqa: ANN001
                    prog: str) -> str:
    """A column named by its option, or by ``--role COL=ROLE``; both must agree."""
    named = given.column_of(role)
    if value is not None and named is not None and value != named:
        raise UsageError(f"{prog}: {option}: expected the column given --role {named}={role}, "
                         f"found {value!r}")
    if value is None and named is None:
        raise UsageError(f"{prog}: {option}: expected the {role} column ({option} COL or --role "
                         f"COL={role}), found neither")
    return value or named


def _cmd_lugre(args: argparse.Namespace) -> int:
    from edm_sym.application.progress import ProgressReporter
    from edm_sym.application.summary import print_summary
    from edm_sym.core.data import join_logs
    from edm_sym.core.errors import ConfigError
    from edm_sym.core.result import target_name_problem
    from edm_sym.core.units import axis_units
    from edm_sym.engines.abstraction.holdout import log_starts
    from edm_sym.engines.lugre import (
        identify_lugre,
        save_lugre,
        shape_bound_flags,
        simulate_lugre,
        weighted_rmse,
    )
    from edm_sym.engines.sources import load_data

    given = _columns(args)
    target = _option_or_role(args.target, given, "target", "--target", "edm lugre")
    velocity = _option_or_role(args.velocity, given, "velocity", "--velocity", "edm lugre")
    for option, name in (("--target", target), ("--velocity", velocity)):
        problem = target_name_problem(name)  # the names LUGRE.json records, as a result's
        if problem:
            raise ConfigError(option, f"{name!r}: {problem}")
    if velocity == target:
        raise UsageError(f"edm lugre: --velocity: expected a column other than the target "
                         f"{target!r}, found it")
    check_outputs([args.output], args.data)
    logs = [load_data(spec, ts=args.ts, require=[target, velocity], columns=given,
                      names=args.columns) for spec in args.data]
    for log in logs:
        log.require_varying([velocity])  # named by file and column, before the fit
    # Several logs: one sample time and column roles (exit 2 naming the file), laid end to
    # end, each simulated from rest.
    data = logs[0] if len(logs) == 1 else join_logs(logs, [target, velocity])
    starts = log_starts(logs)
    with ProgressReporter("edm lugre", quiet=args.quiet) as reporter, \
            data.naming(target=target, velocity=velocity):
        res = identify_lugre(data.columns[target], data.columns[velocity], data.ts,
                             method=args.method, seed=args.seed, time_limit=args.time_limit,
                             progress=reporter.lugre, starts=starts)
    save_lugre(args.output, res, target=target, velocity=velocity,
               data_sha256=data.sha256, seed=args.seed)
    unit = axis_units(args.axis or "rotary").force
    print(f"wrote {args.output}")
    for name, score in (res.comparison or {}).items():
        print(f"{name} fitness {score.fitness:.10g} {unit} ({score.evaluations} evaluations)")
    print(f"rmse {res.rmse:.10g} {unit}")
    if len(logs) > 1:
        for log in logs:
            tau = simulate_lugre(res.params, log.columns[velocity], log.ts)
            print(f"rmse {weighted_rmse(log.columns[target], tau):.10g} {unit} on {log.source}")
    print_summary("edm lugre", fitness=[f"fitness (weighted eq. 8): training {res.rmse:.6g} "
                                        f"{unit}, validation: none held out"],
                  flags=shape_bound_flags(res.params, data.columns[velocity], data.ts))
    return 0


def _cmd_abstract(args: argparse.Namespace) -> int:
    from edm_sym.application.abstract_cli import run_cli
    out = Path(args.output)
    # The checkpoint beside the output is written and, at the end, deleted: never an input.
    check_outputs([out, out.with_name(out.name + ".checkpoint")],
                  [*args.data, *(p for p in (args.config, args.initial) if p)])
    return run_cli(args)


#: Exit statuses of every command (docs/cli.md#exit-status).
EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT, EXIT_INTERRUPTED = 0, 1, 2, 130


#: Where a bug is reported (exit 1 says so).
REPORT_BUG = "this is a bug of edm_sym: please report it with the output of EDM_DEBUG=1"


def _raise_interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt


def _run(argv: Sequence[str] | None, parser: argparse.ArgumentParser) -> int:
    def one_line(message, category, filename, lineno, file=None, line=None) -> None:  # noqa: ANN001
        print(f"{parser.prog}: warning: {as_options(' '.join(str(message).split()))}",
              file=sys.stderr)

    with warnings.catch_warnings():
        warnings.showwarning = one_line
        return _dispatch(argv, parser)


def _files_named(argv: Sequence[str] | None) -> str:
    """The command's arguments that name existing files, for a message that has no file of its own."""
    args = list(sys.argv[1:] if argv is None else argv)
    files = [a for a in args if not a.startswith("-") and Path(a).is_file()]
    return ", ".join(files) or "input"


def _from_interrupt(exc: BaseException) -> bool:
    """Whether ``exc`` wraps a Ctrl-C or SIGTERM: Python 3.11 turns a KeyboardInterrupt
    raised while a class is built (``__set_name__`` of a dataclass field, during a lazy
    import) into a RuntimeError whose cause it is."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return True
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return False


def _dispatch(argv: Sequence[str] | None, parser: argparse.ArgumentParser) -> int:
    try:
        args = parser.parse_args(argv)
        if "" in (getattr(args, "output", None), getattr(args, "out_dir", None)):
            # Not "no -o": a command's default name could then replace a file of the user's.
            raise UsageError(f"{parser.prog}: -o: expected a file or folder name, found an "
                             "empty one")
        return int(args.func(args) or 0)
    except (EdmError, ValueError) as exc:
        if not isinstance(exc, EdmError) and not _raised_by_edm_sym(exc):
            return _failed(parser.prog, exc)  # a library's own check: input edm_sym let through
        if isinstance(exc, ToolMissingError):
            print(f"{parser.prog}: {as_options(str(exc))}", file=sys.stderr)
            return EXIT_FAILED
        if os.environ.get("EDM_DEBUG"):
            traceback.print_exc()
        # ValueError here comes from validation inside the library: bad input. The library
        # names its parameters; the command names the options that give them, also where a
        # log's error names one after the file (log.csv: ts).
        text = str(exc)
        if isinstance(exc, DataFormatError):
            text = f"{where_as_options(exc.where)}: {exc.problem}"
        line = as_options(" ".join(text.split()))
        print(line if isinstance(exc, UsageError) else f"{parser.prog}: {line}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        return _interrupted(parser.prog)
    except ExternalToolError as exc:  # LaTeX or a compiler failed: the work failed, not edm_sym
        print(f"{parser.prog}: {' '.join(str(exc).split())}", file=sys.stderr)
        return EXIT_FAILED
    except RecursionError:
        print(f"{parser.prog}: {_files_named(argv)}: {TOO_DEEP}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except MemoryError:
        print(f"{parser.prog}: {_files_named(argv)}: the work does not fit in this machine's memory; "
              "use a shorter log or smaller sizes", file=sys.stderr)
        return EXIT_BAD_INPUT
    except OSError as exc:  # a file the command could not read or write
        where = exc.filename if exc.filename else _files_named(argv)
        print(f"{parser.prog}: {where}: {exc.strerror or exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except Exception as exc:  # the work itself failed: one line, exit 1
        return _failed(parser.prog, exc)


def _failed(prog: str, exc: Exception) -> int:
    """Exit 1 with one line for an error edm_sym did not expect (or 130 for a wrapped Ctrl-C)."""
    if _from_interrupt(exc):
        return _interrupted(prog)
    if os.environ.get("EDM_DEBUG"):
        traceback.print_exc()
    print(f"{prog}: failed: {type(exc).__name__}: {' '.join(str(exc).split())} "
          f"({REPORT_BUG})", file=sys.stderr)
    return EXIT_FAILED


def _raised_by_edm_sym(exc: BaseException) -> bool:
    """Whether a ValueError was raised in edm_sym's own code (its validation: bad input).

    One raised inside a library (matplotlib's "Axis limits cannot be NaN", the JSON
    encoder's "Out of range float values") is input edm_sym should have refused, or a
    defect: it names no file or field, so it is reported as a failure, not as bad input.
    A built-in's (``float("x")``) has no frame of its own: its caller's counts.
    """
    tb = exc.__traceback__
    last = None
    while tb is not None:
        last = tb.tb_frame.f_code.co_filename
        tb = tb.tb_next
    return last is not None and Path(last).resolve().is_relative_to(_PACKAGE)


_PACKAGE = Path(__file__).resolve().parents[1]


def _interrupted(prog: str) -> int:
    """The end of an interrupted command: one line, exit 130."""
    print(f"{prog}: interrupted", file=sys.stderr)
    return EXIT_INTERRUPTED


def _interruptible(prog: str, body: Callable[[], int]) -> int:
    """Run a whole command, start-up included, so that SIGINT and SIGTERM end it with 130.

    The one place a command's interrupts are set up: SIGTERM (a job scheduler,
    ``kill``) raises KeyboardInterrupt like Ctrl-C, so it ends a command the
    same way (``edm abstract`` writes its best result and keeps its
    checkpoint). The handler is installed before the parser is built and
    before any heavy import (``edm_sym`` imports nothing heavy itself), and
    an interrupt that arrives outside :func:`_dispatch` (building the parser,
    printing a message) still ends in one line, never a traceback.
    """
    import signal

    old = signal.signal(signal.SIGTERM, _raise_interrupt)
    try:
        return body()
    except KeyboardInterrupt:
        return _interrupted(prog)
    finally:
        signal.signal(signal.SIGTERM, old)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``edm``."""
    return _interruptible("edm", lambda: _run(argv, build_parser()))


def export_main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``edm-export`` (the same as ``edm export``)."""
    return _interruptible("edm-export", lambda: _run(argv, _export_parser()))


def _process(entry: Callable[[], int]) -> int:
    """Run an entry point as a whole process: once its status is known, a late Ctrl-C or
    SIGTERM is ignored, so none can fire while the interpreter shuts down (threads and
    extension modules being torn down) and turn exit 130 into a crash or a signal death."""
    import signal

    code = entry()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, signal.SIG_IGN)
    if code == EXIT_INTERRUPTED:
        # The work is cleaned up (checkpoint kept, no temporaries) and the message written.
        # Leave at once: a KeyboardInterrupt that went through an exec of source text
        # (dataclasses and namedtuple build their methods so, during a lazy import) leaves
        # CPython's "unhandled interrupt" mark set, and the normal shutdown would then kill
        # the process with SIGINT (status -2) instead of exiting 130.
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    return code


def run() -> int:
    """The ``edm`` console script and ``python -m edm_sym``: :func:`main` as a process."""
    return _process(main)


def export_run() -> int:
    """The ``edm-export`` console script: :func:`export_main` as a process."""
    return _process(export_main)


def _export_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="edm-export", description="Render an EDM result as C, Python or LaTeX.",
                     epilog="examples:\n  edm-export result.json --target c\n"
                            "  edm-export result.json --target all --pdf -o gen/\n"
                            "docs: docs/cli.md#edm-export",
                     formatter_class=argparse.RawDescriptionHelpFormatter)
    _add_version(parser)
    _add_export_args(parser)
    return parser


if __name__ == "__main__":  # pragma: no cover
    sys.exit(run())
