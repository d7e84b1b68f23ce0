"""The whole flow in one command: data -> LuGre -> EDM -> evaluation -> export.

``edm pipeline PIPELINE.toml`` reproduces the paper's experiment (section IV)
from a small TOML file of data (never code)::

    [data]
    abstraction = "plant:auger/abstraction"   # a file, a simulated plant log, or a list of them
    evaluation = "plant:auger/evaluation"     # (a list: each log simulated from rest)
    axis = "rotary"                           # or "linear" (the units; default rotary)

    [columns]                                 # optional: COLUMN = "ROLE" (docs/data.md)
    tau_ext = "target"

    [abstraction]                             # edm abstract
    config = "abstraction.toml"
    target = "tau_ext"
    inputs = ["theta_w", "theta_uw", "omega", "alpha"]
    seed = 1

    [lugre]                                   # edm lugre (the baseline)
    velocity = "omega"
    weighting = { windows = [[0.0, 10.0, 1.0]], otherwise = 0.0 }

    [export]                                  # edm-export
    target = "all"
    pdf = true

It writes ``lugre.json``, ``result.json`` and ``evaluation.json`` beside the
TOML file, and exports into ``generated/<folder of the TOML file>/``. The
result records its data and LuGre file (``report_inputs``; a kind's log only
when it is one), so a plain ``edm-export result.json --target all``
reproduces the same report.
"""

from __future__ import annotations

import json
import math
import os
import sys
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from edm_sym.application.summary import with_physics
from edm_sym.core.data import ColumnRoles, DataLog, is_plant_spec, join_logs, match_sample_time
from edm_sym.core.errors import TARGET_AS_INPUT, ConfigError, DataFormatError, OutputError
from edm_sym.core.fileio import check_outputs, read_toml, write_atomic
from edm_sym.core.fitness import rms
from edm_sym.engines.sources import load_data

if TYPE_CHECKING:
    from edm_sym.engines.abstraction.parallel import Parallel

SECTIONS = {
    "data": {"abstraction", "evaluation", "axis"},
    "abstraction": {"config", "target", "inputs", "seed", "time_limit"},
    "lugre": {"velocity", "method", "seed", "time_limit", "weighting"},
    "export": {"target", "pdf", "out_dir", "prefix", "real"},
}


@dataclass(frozen=True)
class Pipeline:
    """A parsed pipeline file; paths are resolved against its folder."""

    folder: Path
    abstraction_data: tuple[str, ...]
    evaluation_data: tuple[str, ...]
    target: str
    inputs: tuple[str, ...]
    config: Path | None = None
    seed: int = 0
    time_limit: float | None = None
    lugre: Mapping[str, Any] | None = None
    export: Mapping[str, Any] = field(default_factory=dict)
    columns: ColumnRoles = field(default_factory=ColumnRoles)
    axis: str = "rotary"

    def data_path(self, spec: str) -> str | Path:
        """A data spec as :func:`~edm_sym.core.data.load_data` takes it."""
        return spec if is_plant_spec(spec) else self.folder / spec


def _get(where: str, table: Mapping[str, Any], key: str, kind: type | tuple, default: Any = ...) -> Any:
    if key not in table:
        if default is ...:
            raise ConfigError(f"{where}.{key}", "expected this key, found it missing")
        return default
    value = table[key]
    if isinstance(value, bool) and kind is not bool or not isinstance(value, kind):
        names = kind.__name__ if isinstance(kind, type) else " or ".join(k.__name__ for k in kind)
        raise ConfigError(f"{where}.{key}", f"expected {names}, found {value!r}")
    if isinstance(value, str) and not value.strip():  # not taken for the key left out
        raise ConfigError(f"{where}.{key}", f"expected a non-empty {kind.__name__}, found "
                                            f"{value!r}")
    return value


def load_pipeline(path: str | Path) -> Pipeline:
    """Read and validate a pipeline TOML file.

    Raises
    ------
    ConfigError
        Naming the file and key, with what was expected and found.
    """
    path = Path(path)
    doc = read_toml(path, ConfigError, where=str(path))
    name = path.name
    for section, table in doc.items():
        if section == "columns":
            continue
        if section not in SECTIONS:
            raise ConfigError(f"{name}: {section}",
                              f"expected one of the sections {', '.join(SECTIONS)}, columns, "
                              f"found {section!r}")
        if not isinstance(table, dict):
            raise ConfigError(f"{name}: {section}", f"expected a table, found {table!r}")
        for key in table:
            if key not in SECTIONS[section]:
                raise ConfigError(f"{name}: {section}.{key}", f"expected one of "
                                  f"{', '.join(sorted(SECTIONS[section]))}, found {key!r}")
    data, abst = doc.get("data", {}), doc.get("abstraction", {})
    abstraction_data = _logs(f"{name}: data", data, "abstraction", required=True)
    evaluation_data = _logs(f"{name}: data", data, "evaluation", required=False)
    config = _get(f"{name}: abstraction", abst, "config", str, None)
    # The abstraction config's [columns] and axis, under the pipeline's own.
    base = None
    if config:
        from edm_sym.engines.abstraction import load_config

        try:
            base = load_config(path.resolve().parent / config)
        except ConfigError as exc:  # named as the pipeline's key, then the config's own message
            raise ConfigError(f"{name}: abstraction.config", str(exc)) from None
    axis = _get(f"{name}: data", data, "axis", str, None) or (base.axis if base else None) or "rotary"
    if axis not in ("rotary", "linear"):
        raise ConfigError(f"{name}: data.axis", f"expected rotary or linear, found {axis!r}")
    try:
        columns = ColumnRoles.from_table(f"{name}: columns", doc.get("columns", {})).over(
            base.columns if base else None)
    except DataFormatError as exc:
        raise ConfigError(exc.where, exc.problem) from None
    target = _get(f"{name}: abstraction", abst, "target", str, None) or columns.target
    if target is None:
        raise ConfigError(f"{name}: abstraction.target", "expected this key (or a column with "
                          "the role \"target\" in [columns]), found neither")
    try:
        columns = columns.with_role(target, "target")
    except DataFormatError as exc:
        raise ConfigError(exc.where, exc.problem) from None
    inputs = _get(f"{name}: abstraction", abst, "inputs", list, None)
    if inputs is None:
        inputs = list(columns.inputs)
    if not inputs or not all(isinstance(i, str) for i in inputs):
        raise ConfigError(f"{name}: abstraction.inputs", f"expected column names (or columns "
                          f"with an input role in [columns]), found {inputs!r}")
    if target in inputs:
        raise ConfigError(f"{name}: abstraction.inputs", TARGET_AS_INPUT.format(target=target))
    limit = _get(f"{name}: abstraction", abst, "time_limit", (int, float), None)
    if limit is not None and not (math.isfinite(limit) and limit > 0):
        raise ConfigError(f"{name}: abstraction.time_limit",
                          f"expected a number of seconds > 0, found {limit}")
    seed = _get(f"{name}: abstraction", abst, "seed", int, 0)
    if not 0 <= seed < 2**32:
        raise ConfigError(f"{name}: abstraction.seed", f"expected an integer >= 0 and < 2**32, found {seed}")
    # The later stages' settings are checked now, before any of the long work.
    if "lugre" in doc:
        _check_lugre(name, doc["lugre"])
    _check_export(name, doc.get("export", {}))
    return Pipeline(
        folder=path.resolve().parent,
        abstraction_data=abstraction_data,
        evaluation_data=evaluation_data,
        target=target,
        inputs=tuple(inputs),
        config=path.resolve().parent / config if config else None,
        seed=seed,
        time_limit=float(limit) if limit is not None else None,
        lugre=doc.get("lugre"),
        export=doc.get("export", {}),
        columns=columns,
        axis=axis,
    )




def _logs(where: str, table: Mapping[str, Any], key: str, *, required: bool) -> tuple[str, ...]:
    """A ``[data]`` key: one log (a string) or several (a list of strings)."""
    if isinstance(table.get(key), str):
        return (_get(where, table, key, str),)
    value = _get(where, table, key, (str, list), ... if required else None)
    if value is None:
        return ()
    if not value or not all(isinstance(v, str) and v.strip() for v in value):
        raise ConfigError(f"{where}.{key}", f"expected a log or a list of one or more logs, "
                                            f"found {value!r}")
    return tuple(value)


def _check_lugre(name: str, table: Mapping[str, Any]) -> None:
    """Refuse a bad ``[lugre]`` value, naming the file and key (before anything runs)."""
    from edm_sym.engines.abstraction.weighting import parse_weighting
    from edm_sym.engines.lugre import METHODS

    where = f"{name}: lugre"
    _get(where, table, "velocity", str)
    method = _get(where, table, "method", str, "scipy")
    if method not in METHODS and method != "both":
        raise ConfigError(f"{where}.method", f"expected one of "
                          f"{', '.join(sorted([*METHODS, 'both']))}, found {method!r}")
    seed = _get(where, table, "seed", int, 0)
    if not 0 <= seed < 2**32:
        raise ConfigError(f"{where}.seed", f"expected an integer >= 0 and < 2**32, found {seed}")
    limit = _get(where, table, "time_limit", (int, float), None)
    if limit is not None and not (math.isfinite(limit) and limit >= 0):
        raise ConfigError(f"{where}.time_limit", f"expected a number of seconds >= 0, found {limit}")
    if "weighting" in table:
        parse_weighting(f"{where}.weighting", table["weighting"])


def _check_export(name: str, table: Mapping[str, Any]) -> None:
    """Refuse a bad ``[export]`` value, naming the file and key (before anything runs)."""
    from edm_sym.outputs.printing import REALS
    from edm_sym.outputs.render import TARGET_NAMES
    from edm_sym.outputs.render.context import prefix_problem

    where = f"{name}: export"
    target = _get(where, table, "target", str, "all")
    if target not in TARGET_NAMES:
        raise ConfigError(f"{where}.target",
                          f"expected one of {', '.join(TARGET_NAMES)}, found {target!r}")
    prefix = _get(where, table, "prefix", str, "edm_comp")
    problem = prefix_problem(prefix)
    if problem:
        raise ConfigError(f"{where}.prefix", f"{problem}, found {prefix!r}")
    real = _get(where, table, "real", str, "double")
    if real not in REALS:
        raise ConfigError(f"{where}.real", f"expected one of {', '.join(REALS)}, found {real!r}")
    _get(where, table, "pdf", bool, False)
    _get(where, table, "out_dir", str, "")


def _lugre_weights(spec: Any, data: DataLog, target: str, where: str) -> Any:
    if spec is None:
        return None
    from edm_sym.engines.abstraction.weighting import parse_weighting

    weighting = parse_weighting(where, spec)
    w = weighting.weights(data.times, data.columns[target])
    w = np.broadcast_to(np.asarray(w, dtype=float), (len(data),)).copy()
    if not np.any(w > 0.0):  # identify_lugre refuses it too, but could not name the key
        raise ConfigError(where, f"expected a weighting above zero somewhere on {data.source}, "
                                 f"found zero on all {len(w)} samples")
    return w


def _scores(errors: Mapping[str, np.ndarray]) -> dict[str, float]:
    """The RMSE of each model's residual (and EDM/LuGre when both are there)."""
    row = {kind: rms(e) for kind, e in errors.items()}
    if "lugre" in row:
        row["ratio"] = row["edm"] / row["lugre"]
    return row


def _report_logs(pipe: Pipeline) -> dict[str, list[str | Path]]:
    """The report's logs of a kind given several (one of each is recorded in the result)."""
    out = {}
    for key, specs in (("data", pipe.abstraction_data), ("eval_data", pipe.evaluation_data)):
        if len(specs) > 1:
            out[key] = [pipe.data_path(s) for s in specs]
    return out


def run_pipeline(path: str | Path, *, progress: bool = True, reuse: bool = False,
                 out: Any = None, axis: str | None = None,
                 parallel: Parallel | None = None) -> dict[str, Any]:
    """Run the whole flow of a pipeline file.

    Parameters
    ----------
    path : path-like
        The pipeline TOML file.
    progress : bool
        Show the progress of the LuGre identification and the genetic
        algorithm on stderr (a bar on a terminal, a line every few seconds
        elsewhere).
    reuse : bool
        Keep an existing ``lugre.json`` / ``result.json`` beside the file
        instead of identifying again (evaluation and export still run); an
        interrupted ``result.json`` is not kept but continued from its
        checkpoint ``result.json.checkpoint``.
    out : file, optional
        Where the files written and the RMSE table are printed (default:
        standard output); the fitness and the flags go to standard error.
    axis : str, optional
        ``"rotary"`` or ``"linear"`` over the file's ``[data] axis`` (``--axis``).
    parallel : Parallel, optional
        Where the abstraction's work goes (:class:`~edm_sym.engines.abstraction.Parallel`;
        default: this machine's cores).

    Returns
    -------
    dict
        The evaluation summary (also written to ``evaluation.json``).
    """
    run = _PipelineRun.start(path, progress=progress, reuse=reuse,
                             out=out if out is not None else sys.stdout, axis=axis)
    run.check_before_work()
    lugre = run.identify_lugre()
    result = run.abstraction(lugre, parallel)
    summary = run.evaluate(result, lugre)
    run.export(result, lugre)
    return summary


@dataclass
class _PipelineRun:
    """One run of a pipeline file: its logs and output files, and the flow's steps in order."""

    path: str | Path
    pipe: Pipeline
    progress: bool
    reuse: bool
    out: Any
    logs: dict[str, list[DataLog]]
    #: The abstraction logs as one (several: laid end to end, each simulated from rest).
    abst: DataLog
    lugre_file: Path
    result_file: Path
    checkpoint: Path
    out_dir: Path
    #: Whether --reuse keeps the result.json there (not an interrupted one: it is continued).
    keep_result: bool = False
    config: Any = None

    @property
    def name(self) -> str:
        """The pipeline file's name, for messages."""
        return Path(self.path).name

    @property
    def abst_logs(self) -> list[DataLog]:
        """The abstraction logs, each on its own."""
        return self.logs["abstraction"]

    @classmethod
    def start(cls, path: str | Path, *, progress: bool, reuse: bool, out: Any,
              axis: str | None) -> _PipelineRun:
        """The pipeline file read and its logs loaded; where every output goes."""
        pipe = load_pipeline(path)
        if axis is not None:  # --axis, over the file's
            pipe = replace(pipe, axis=axis)

        def load(spec: str) -> DataLog:
            return load_data(pipe.data_path(spec), require=[*pipe.inputs, pipe.target],
                             columns=pipe.columns)

        logs = {"abstraction": [load(spec) for spec in pipe.abstraction_data]}
        if pipe.evaluation_data:
            logs["evaluation"] = [load(spec) for spec in pipe.evaluation_data]
        abst_logs = logs["abstraction"]
        # Several logs: one sample time and column roles (exit 2 naming the file); each is
        # simulated from rest on its own.
        abst = abst_logs[0] if len(abst_logs) == 1 else join_logs(abst_logs,
                                                                    [pipe.target, *pipe.inputs])
        result_file = pipe.folder / "result.json"
        ex = pipe.export
        out_dir = Path(os.path.normpath(pipe.folder / ex["out_dir"])) if "out_dir" in ex else \
            Path("generated") / pipe.folder.name
        return cls(path, pipe, progress, reuse, out, logs, abst, pipe.folder / "lugre.json",
                   result_file, result_file.with_name(result_file.name + ".checkpoint"), out_dir)

    def check_before_work(self) -> None:
        """What the abstraction, the evaluation and the export will refuse, refused before any
        work: a refused pipeline leaves the outputs of an earlier run as they were."""
        from edm_sym.core.result import load_result
        from edm_sym.engines.abstraction import default_config, load_config
        from edm_sym.engines.abstraction.checkpoint import read_checkpoint
        from edm_sym.engines.abstraction.run import check_budget, check_data, check_inputs
        from edm_sym.engines.abstraction.searches import checkpoint_files

        pipe, name = self.pipe, self.name
        try:
            check_inputs(pipe.target, pipe.inputs)
        except ConfigError as exc:
            raise ConfigError(f"{name}: abstraction.{exc.where}", exc.problem) from None
        for log in self.abst_logs:
            check_data(log, pipe.target, pipe.inputs)
        for log in self.logs.get("evaluation", []):
            match_sample_time(log, self.abst.ts, model=str(self.abst_logs[0].source))
        self._check_outputs()
        # An interrupted abstraction left the best so far and its checkpoint: --reuse continues it.
        self.keep_result = self.reuse and self.result_file.exists() and \
            load_result(self.result_file).provenance.get("stop_reason") != "interrupted"
        # The abstraction's sizes are checked before the LuGre identification runs.
        self.config = load_config(pipe.config) if pipe.config else None
        if not self.keep_result:
            check_budget(self.config or default_config(), len(self.abst), len(pipe.inputs),
                         time_limit=pipe.time_limit, ts=float(self.abst.ts))
        if self.reuse and not self.keep_result:
            # A checkpoint --reuse cannot continue is refused before the LuGre identification
            # (whether it is of this run is known once the abstraction has the training samples).
            count = (self.config or default_config()).searches
            for f in checkpoint_files(self.checkpoint, count):
                if f is not None and f.exists():
                    read_checkpoint(f)

    def _check_outputs(self) -> None:
        """Every output is checked before the long work: none may be an input, all must be
        writable."""
        pipe, out_dir = self.pipe, self.out_dir
        data_files = [pipe.data_path(s) for s in (*pipe.abstraction_data, *pipe.evaluation_data)]
        prefix = pipe.export.get("prefix", "edm_comp")
        inputs = [self.path, pipe.config, *data_files]
        check_outputs([self.lugre_file, self.result_file, self.checkpoint,
                       pipe.folder / "evaluation.json", out_dir / f"{prefix}.h"], inputs,
                      option="pipeline output")
        # Every file the export writes is <out_dir>/<prefix>... (.c, .py, the report, its figures).
        for src in (Path(i) for i in inputs if i is not None and not str(i).startswith("plant:")):
            if src.exists() and src.resolve().parent == out_dir.resolve() and \
                    src.name.startswith(prefix):
                raise OutputError(f"pipeline output {out_dir / prefix}*: expected the export's "
                                  f"files apart from the inputs, found the input {src} among the "
                                  "names it writes (writing would destroy it); choose another "
                                  "out_dir or prefix")

    def identify_lugre(self) -> Any:
        """The LuGre baseline (``[lugre]``): identified, or with --reuse the one there; None
        without the table."""
        from edm_sym.application.progress import ProgressReporter
        from edm_sym.engines.abstraction.holdout import log_starts
        from edm_sym.engines.lugre import identify_lugre, load_lugre, save_lugre

        pipe, name, abst_logs = self.pipe, self.name, self.abst_logs
        if pipe.lugre is None:
            return None
        velocity = _get(f"{name}: lugre", pipe.lugre, "velocity", str)
        if velocity == pipe.target:  # as edm lugre --velocity
            raise ConfigError(f"{name}: lugre.velocity", f"expected a column other than the "
                                                         f"target {velocity!r}, found it")
        for log in abst_logs:
            log.require_varying([velocity])  # a constant column, or the clock, is no velocity
        lugre_data = abst_logs[0] if len(abst_logs) == 1 else join_logs(abst_logs,
                                                                         [pipe.target, velocity])
        if not (self.reuse and self.lugre_file.exists()):
            seed = _get(f"{name}: lugre", pipe.lugre, "seed", int, 0)
            spec = pipe.lugre.get("weighting")
            weights = None if spec is None else np.concatenate([
                _lugre_weights(spec, log, pipe.target, f"{name}: lugre.weighting")
                for log in abst_logs])
            with ProgressReporter("edm pipeline", quiet=not self.progress) as reporter, \
                    lugre_data.naming(target=pipe.target, velocity=velocity):
                res = identify_lugre(
                    lugre_data.columns[pipe.target],
                    lugre_data.column(velocity, role="velocity column"),
                    lugre_data.ts,
                    method=_get(f"{name}: lugre", pipe.lugre, "method", str, "scipy"),
                    seed=seed,
                    time_limit=_get(f"{name}: lugre", pipe.lugre, "time_limit", (int, float), None),
                    weights=weights, progress=reporter.lugre, starts=log_starts(abst_logs))
            save_lugre(self.lugre_file, res, target=pipe.target, velocity=velocity,
                       data_sha256=lugre_data.sha256, seed=seed)
        lugre = load_lugre(self.lugre_file)
        print(f"lugre: {self.lugre_file}", file=self.out)
        return lugre

    def abstraction(self, lugre: Any, parallel: Parallel | None) -> Any:
        """The EDM result: found (``result.json`` written with the logs it records), or with
        --reuse the one there.

        Raises
        ------
        KeyboardInterrupt
            When the abstraction was interrupted (its best so far is written).
        """
        from edm_sym.application.progress import ProgressReporter
        from edm_sym.core.result import load_result, save_result
        from edm_sym.engines.abstraction import abstract

        pipe, abst_logs = self.pipe, self.abst_logs
        if not self.keep_result:
            with ProgressReporter("edm pipeline", quiet=not self.progress) as reporter:
                result = abstract(abst_logs[0] if len(abst_logs) == 1 else abst_logs,
                                  target=pipe.target, inputs=pipe.inputs, config=self.config,
                                  seed=pipe.seed, time_limit=pipe.time_limit,
                                  callback=reporter.abstraction,
                                  checkpoint=self.checkpoint, resume=self.reuse, axis=pipe.axis,
                                  parallel=parallel)
            # The result records one log of each kind; several are given to the export here.
            stored = {}
            if len(pipe.abstraction_data) == 1:
                stored["data"] = pipe.abstraction_data[0]
            if len(pipe.evaluation_data) == 1:
                stored["eval_data"] = pipe.evaluation_data[0]
            if lugre is not None:
                stored["lugre"] = self.lugre_file.name
            logs = self.abst_logs
            result, _ = with_physics(result, logs[0] if len(logs) == 1 else logs)
            save_result(replace(result, report_inputs=stored), self.result_file)
            if result.provenance.get("stop_reason") == "interrupted":
                # The best result so far is saved; the rest of the flow must not run on it.
                raise KeyboardInterrupt
        result = load_result(self.result_file)
        print(f"result: {self.result_file}", file=self.out)
        return result

    def evaluate(self, result: Any, lugre: Any) -> dict[str, Any]:
        """The RMSE of EDM (and LuGre) on every log, written to ``evaluation.json`` and printed
        as a table."""
        from edm_sym.engines.models import model_of

        pipe, out = self.pipe, self.out
        summary: dict[str, Any] = {}
        models = {"edm": model_of(result)} | ({"lugre": model_of(lugre)} if lugre is not None
                                               else {})
        for label, kind_logs in self.logs.items():
            for log in kind_logs:  # where the model reads inputs beyond what it learnt from
                for line in models["edm"].beyond_ranges(log):
                    print(line, file=out)
            # Each log simulated from rest; several logs give a row each and one over all.
            errors = {kind: [log.columns[pipe.target] - m.run(log).torque for log in kind_logs]
                      for kind, m in models.items()}
            if len(kind_logs) > 1:
                for k, log in enumerate(kind_logs):
                    src = str(log.source)
                    shown = src if is_plant_spec(src) else Path(src).name
                    summary[f"{label}: {shown}"] = _scores(
                        {kind: e[k] for kind, e in errors.items()})
            summary[label] = _scores({kind: np.concatenate(e) for kind, e in errors.items()})
        write_atomic(pipe.folder / "evaluation.json",
                     json.dumps(summary, sort_keys=True, indent=2) + "\n")
        width = max(12, *(len(label) for label in summary))
        print(f"{'log':<{width}} {'EDM RMSE':>12} {'LuGre RMSE':>12} {'EDM/LuGre':>10}", file=out)
        for label, row in summary.items():
            lug = f"{row['lugre']:12.4g} {row['ratio']:10.3f}" if "lugre" in row else ""
            print(f"{label:<{width}} {row['edm']:12.4g} {lug}", file=out)
        return summary

    def export(self, result: Any, lugre: Any) -> None:
        """The export (``[export]``), then the closing summary: fitness and flags."""
        from edm_sym.application.exporting import export
        from edm_sym.application.summary import fitness_line, print_summary, result_flags
        from edm_sym.engines.lugre import shape_bound_flags

        pipe, name, ex = self.pipe, self.name, self.pipe.export
        written = export(result, _get(f"{name}: export", ex, "target", str, "all"), self.out_dir,
                         prefix=_get(f"{name}: export", ex, "prefix", str, "edm_comp"),
                         real=_get(f"{name}: export", ex, "real", str, "double"),
                         pdf=_get(f"{name}: export", ex, "pdf", bool, False),
                         **_report_logs(pipe))
        for p in written:
            print(f"wrote {p}", file=self.out)
        judged = self.logs.get("evaluation", self.abst_logs)
        flags = result_flags(result, judged[0] if len(judged) == 1 else judged)
        if lugre is not None:
            velocity = np.concatenate([log.columns[lugre.velocity_name] for log in self.abst_logs])
            flags += shape_bound_flags(lugre.params, velocity, self.abst.ts)
        print_summary("edm pipeline", fitness=[fitness_line(result)], flags=flags,
                      describe=self.result_file)
