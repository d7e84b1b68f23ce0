"""result.json: the abstraction result (docs/result-format.md).

Loading validates against the JSON Schema shipped in the package, then checks
what a schema cannot (known element codes, names matching codes, shapes
matching counts, ranges usable), and refuses a bad file with a
:class:`~edm_sym.core.errors.ResultFormatError` naming the file and field.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Any

from edm_sym.core.bounds import bound_flags
from edm_sym.core.data import ColumnRoles
from edm_sym.core.elements import REGISTRY, ParamRange, check_range
from edm_sym.core.errors import DataFormatError, ResultFormatError
from edm_sym.core.fileio import json_kind, read_json, write_atomic
from edm_sym.core.matrix import Compensator, ElementMatrix, Gene, Row
from edm_sym.core.units import AXES, AxisUnits, axis_units
from edm_sym.core.validation import json_path, positive_number, schema_problem

FORMAT = "edm-result"
VERSION = 1


@dataclass(frozen=True)
class StepRecord:
    """One hierarchical step: its best matrix and fitness history (paper, Fig. 17)."""

    step: int
    matrix: ElementMatrix
    fitness: float
    history: tuple[float, ...]
    generations: int = 0
    evaluations: int = 0
    weighting: Mapping[str, Any] = field(default_factory=dict)


#: The widest header line of an EdmResult's repr.
HEADER_WIDTH = 119


@dataclass(frozen=True)
class EdmResult:
    """A loaded (or freshly found) abstraction result.

    Parameters
    ----------
    compensator : Compensator
        The matrix, sample time and parameter ranges.
    target : str
        The name of the target column (the estimated external torque).
    steps : tuple of StepRecord
        The hierarchical steps, in order (empty for a hand-written model).
    provenance : mapping
        ``seed``, ``package_version``, ``data_sha256`` (and optional extras).
    fitness : float or None
        The final fitness (eq. 8) on the abstraction data.
    report_inputs : mapping of str to str
        Optional ``data``, ``eval_data`` (paths relative to the result's
        folder, or ``plant:...`` specs) and ``lugre`` (a LUGRE.json path):
        what the report shows when ``edm-export`` is given no such options.
    validation : mapping
        What was held out from the GA and the exported model's training and
        validation scores (see :mod:`edm_sym.engines.abstraction.holdout`); empty
        in results written before held-out validation existed.
    parsimony : mapping
        The pruning pass's complexity-vs-fitness front, the selection rule
        and the selected member (see :mod:`edm_sym.engines.abstraction.prune`);
        empty when there was none.
    sha256 : str or None
        The sha256 of the file it was loaded from.
    axis : str
        ``"rotary"`` (the default, and what a file without ``axis`` means) or
        ``"linear"``: which SI units the target and the inputs are in
        (:func:`edm_sym.core.units.axis_units`, docs/data.md#units).
    logs : tuple of mapping
        Provenance of every log the abstraction used
        (:meth:`edm_sym.core.data.DataLog.record`): ``use``, ``file``,
        ``sha256``, ``rows``, ``sample_time`` and ``columns`` with their roles;
        empty for a hand-written model.
    physics : mapping
        The laws the model holds by its behaviour on the abstraction logs'
        motion (:func:`edm_sym.engines.physics.physics_on_log`, the ``physics``
        key of ``edm describe --json``), as ``edm abstract`` printed them;
        empty when not measured (a hand-written model, an interrupted run).
    """

    compensator: Compensator
    target: str
    steps: tuple[StepRecord, ...] = ()
    provenance: Mapping[str, Any] = field(default_factory=dict)
    fitness: float | None = None
    sha256: str | None = None
    source: str | None = None
    report_inputs: Mapping[str, str] = field(default_factory=dict)
    validation: Mapping[str, Any] = field(default_factory=dict)
    parsimony: Mapping[str, Any] = field(default_factory=dict)
    axis: str = "rotary"
    logs: tuple[Mapping[str, Any], ...] = ()
    physics: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.axis not in AXES:
            raise ResultFormatError("axis", f"expected {' or '.join(AXES)}, found {self.axis!r}")
        object.__setattr__(self, "logs", tuple(self.logs))

    def column_roles(self) -> ColumnRoles | None:
        """The column roles of the abstraction log, to apply to another log of the axis.

        They are ``loose``: a second log takes the recorded time column and
        roles where it has those columns (``edm simulate``, ``edm-export
        --data``, ``edm describe``). None when no log is recorded.
        """
        k = next((k for k, g in enumerate(self.logs) if g.get("use") == "abstraction"), None)
        if k is None:
            return None
        roles = {c["name"]: c["role"] for c in self.logs[k].get("columns", ()) if c.get("role")}
        name = Path(self.source).name if self.source else "result.json"
        return ColumnRoles(roles, f"{name}: logs[{k}].columns", loose=frozenset(roles))

    @property
    def roles(self) -> dict[str, str]:
        """The roles recorded for the inputs (input -> position, velocity, ...);
        inputs without one take the role their name gives (docs/symbolic.md#input-roles)."""
        cols = self.column_roles()
        if cols is None:
            return {}
        return {name: cols.roles[name] for name in self.inputs if name in cols.roles}

    @property
    def observer_bandwidth(self) -> float | None:
        """The observer's bandwidth [rad/s] ``edm abstract`` was told
        (``provenance.observer_bandwidth``, docs/result-format.md), else None."""
        return positive_number(self.provenance.get("observer_bandwidth"))

    @property
    def units(self) -> AxisUnits:
        """The SI units of this result's axis (``axis_units(self.axis)``)."""
        return axis_units(self.axis)

    def __repr__(self) -> str:
        """A header line and one line per row (the dataclass dump would fill the screen).

        The header lists the inputs by name when it stays within ``HEADER_WIDTH``
        characters, else their number (each row line names its input).
        """
        from edm_sym.core.display import matrix_lines

        m = self.compensator.matrix
        val = self.validation.get("validation") if isinstance(self.validation, Mapping) else None
        from edm_sym.core.units import axis_units

        unit = axis_units(getattr(self, "axis", "rotary")).force
        fit = "not recorded" if self.fitness is None else f"{self.fitness:.4g} {unit}"
        if isinstance(val, Mapping) and val.get("fitness") and val["fitness"][0] is not None:
            fit += f", validation {val['fitness'][0]:.4g} {unit}"
        tail = (f"{m.n_elements}x{len(m.rows)} matrix, Ts = {self.sample_time:g} s, "
                f"fitness {fit})")
        head = f"EdmResult(target {self.target!r}, inputs {', '.join(m.inputs)}, {tail}"
        if len(head) > HEADER_WIDTH:  # the rows name the inputs they read
            head = f"EdmResult(target {self.target!r}, {len(m.inputs)} inputs, {tail}"
        return "\n".join([head] + [f"  {line}" for line in matrix_lines(self.compensator)])

    def _repr_latex_(self) -> str | None:
        """The compensator as LaTeX, one row per line (Jupyter; decodes with sympy)."""
        from edm_sym.core.display import latex_repr

        return latex_repr("result", self)

    @property
    def matrix(self) -> ElementMatrix:
        """The final element matrix."""
        return self.compensator.matrix

    @property
    def inputs(self) -> tuple[str, ...]:
        """Input names, in order."""
        return self.compensator.matrix.inputs

    @property
    def sample_time(self) -> float:
        """Ts [s]."""
        return self.compensator.sample_time

    def to_json(self) -> dict[str, Any]:
        """The JSON document (a plain dict) of this result."""
        comp = self.compensator
        return {
            "format": FORMAT,
            "version": VERSION,
            "sample_time": comp.sample_time,
            "record_length": comp.record_length,
            "inputs": list(comp.matrix.inputs),
            "target": self.target,
            "axis": self.axis,
            "fitness": self.fitness,
            "matrix": matrix_to_json(comp.matrix),
            # Every element's range is kept, so a matrix grown later decodes the same.
            "parameter_ranges": {k: v.to_json() for k, v in sorted(comp.ranges.items())},
            "steps": [_step_to_json(s) for s in self.steps],
            "provenance": dict(self.provenance),
            **({"report_inputs": dict(self.report_inputs)} if self.report_inputs else {}),
            **_bounds_block(comp),
            **({"validation": dict(self.validation)} if self.validation else {}),
            **({"parsimony": dict(self.parsimony)} if self.parsimony else {}),
            **({"logs": [dict(g) for g in self.logs]} if self.logs else {}),
            **({"physics": dict(self.physics)} if self.physics else {}),
        }


def recorded_ranges(logs: Sequence[Mapping[str, Any]]) -> tuple[str | None, dict[str, tuple[float, float]]]:
    """The abstraction logs' names (joined by ", ") and each column's recorded (min, max)
    over all of them, from result.json ``logs``: a multi-log abstraction learnt from every log.

    Columns recorded without ``min`` and ``max`` (results written before they
    existed) are left out.
    """
    names: list[str] = []
    ranges: dict[str, tuple[float, float]] = {}
    for log in logs:
        if log.get("use") != "abstraction":
            continue
        names.append(str(log.get("file")))
        for c in log.get("columns", ()):
            if c.get("min") is not None and c.get("max") is not None:
                lo, hi = float(c["min"]), float(c["max"])
                was = ranges.get(c["name"], (lo, hi))
                ranges[c["name"]] = (min(was[0], lo), max(was[1], hi))
    return (", ".join(names) if names else None), ranges


def _bounds_block(comp: Compensator) -> dict[str, Any]:
    """``parameters_at_bound``, derived from the matrix (written only when not empty).

    Loading ignores the key: it is recomputed from the matrix, so it cannot go stale.
    """
    flags = bound_flags(comp)
    return {"parameters_at_bound": [f.to_json() for f in flags]} if flags else {}


def matrix_to_json(matrix: ElementMatrix) -> dict[str, Any]:
    """JSON form of an element matrix."""
    return {
        "n_elements": matrix.n_elements,
        "n_rows": matrix.n_rows,
        "rows": [
            {
                "input": matrix.inputs[r.input],
                "input_code": r.input,
                "elements": [
                    {"name": g.element.name, "code": g.code, "p": g.p} for g in r.genes
                ],
            }
            for r in matrix.rows
        ],
    }


def _step_to_json(s: StepRecord) -> dict[str, Any]:
    return {
        "step": s.step,
        "n_elements": s.matrix.n_elements,
        "n_rows": s.matrix.n_rows,
        "generations": s.generations,
        "evaluations": s.evaluations,
        "weighting": dict(s.weighting),
        "history": list(s.history),
        "fitness": s.fitness,
        "matrix": matrix_to_json(s.matrix),
    }


def dumps(result: EdmResult) -> str:
    """Serialise deterministically: sorted keys, fixed indentation, final newline."""
    return json.dumps(result.to_json(), sort_keys=True, indent=2, allow_nan=False) + "\n"


def save_result(result: EdmResult, path: str | Path) -> Path:
    """Write ``result`` to ``path`` atomically (temporary file, then rename).

    The document is checked as :func:`load_result` checks it before anything
    is written, so a saved file always loads.

    Raises
    ------
    ResultFormatError
        When ``result`` would make a file that :func:`load_result` refuses
        (a result built by hand without ``provenance["seed"]``, say), naming
        the field; nothing is written.
    """
    if not isinstance(result, EdmResult):
        raise ResultFormatError("result", f"expected an EdmResult, found {type(result).__name__}")
    text = dumps(result)
    parse_result(json.loads(text), Path(path).name)
    return write_atomic(path, text)


@lru_cache(maxsize=1)
def schema() -> dict[str, Any]:
    """The JSON Schema of result.json that ships inside the package."""
    text = resources.files("edm_sym").joinpath("schema/result.schema.json").read_text("utf-8")
    return json.loads(text)


#: Input names: C and Python identifiers (they become macros, struct fields and keys).
INPUT_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def input_name_problem(name: str, others: Sequence[str] = ()) -> str | None:
    """Why ``name`` cannot be an input of a result, or None when it can.

    An input name becomes a C macro (``EDM_COMP_INPUT_<NAME>``), a C
    comment and a Python string key, so it must be an ASCII identifier
    (``^[A-Za-z_][A-Za-z0-9_]*$``, as result.json's schema says) that is no
    Python keyword, and no two inputs may differ only in case (their macros
    would be the same).

    Parameters
    ----------
    name : str
    others : sequence of str
        The inputs before it.
    """
    import keyword

    if not INPUT_NAME.fullmatch(name):
        return ("expected a column name made of ASCII letters, digits and '_', not starting with a "
                "digit (it names C macros and Python keys); rename the column")
    if keyword.iskeyword(name):
        return "expected a column name that is no Python keyword; rename the column"
    same = [o for o in others if o.upper() == name.upper()]
    if same:
        return (f"expected names that differ in more than case, found {same[0]!r} too "
                f"(both would be the C macro ..._INPUT_{name.upper()})")
    return None


def target_name_problem(name: str) -> str | None:
    """Why ``name`` cannot be the target column of a result, or None when it can.

    The target's name is printed in every export: a C comment, the Python
    module's docstring and a Python string, the LaTeX report. Every target
    prints any name made of printable characters (any script) without a
    backslash and without three double quotes in a row; a name with one of
    those (or a newline, a tab, another control character) is refused by the
    first command that reads it (docs/data.md#column-names).

    Parameters
    ----------
    name : str
    """
    rule = ("expected a column name of printable characters without a backslash or three "
            "double quotes in a row (it is printed in the C, Python and LaTeX exports)")
    bad = next((c for c in name if not c.isprintable() and c != " "), None)
    if bad is not None:
        return f"{rule}, found the unprintable character U+{ord(bad):04X}; rename the column"
    if "\\" in name:
        return f"{rule}, found a backslash; rename the column"
    if '"""' in name:
        return f"{rule}, found three double quotes in a row; rename the column"
    return None


def format_path(parts: Sequence[Any]) -> str:
    """``["matrix", "rows", 3, "code"]`` -> ``"matrix.rows[3].code"``.

    A key that is not a plain name (a space, a newline, a quote ...) is shown
    JSON-quoted in brackets, ``parameters["a\\nb"]``, so the path stays one line
    (:func:`edm_sym.core.validation.json_path`).
    """
    return json_path(parts) or "(top level)"


def _schema_error(name: str, doc: Any) -> ResultFormatError | None:
    problem = schema_problem(schema(), doc)
    if problem is None:
        return None
    path, text = problem
    return ResultFormatError(f"{name}: {format_path(path)}", text)


def _matrix_from_json(name: str, where: str, doc: Mapping[str, Any],
                      inputs: Sequence[str]) -> ElementMatrix:
    rows = doc["rows"]
    if doc["n_rows"] != len(rows):
        raise ResultFormatError(f"{name}: {where}.n_rows",
                                f"expected the number of rows ({len(rows)}), found {doc['n_rows']}")
    out = []
    for j, r in enumerate(rows):
        rw = f"{where}.rows[{j}]"
        if len(r["elements"]) != doc["n_elements"]:
            raise ResultFormatError(
                f"{name}: {rw}.elements",
                f"expected n_elements = {doc['n_elements']} elements, found {len(r['elements'])}",
            )
        code = r["input_code"]
        if code >= len(inputs):
            raise ResultFormatError(f"{name}: {rw}.input_code",
                                    f"expected 0-{len(inputs) - 1} (inputs), found {code}")
        if r["input"] != inputs[code]:
            raise ResultFormatError(f"{name}: {rw}.input",
                                    f"expected {inputs[code]!r} (inputs[{code}]), found {r['input']!r}")
        genes = []
        for i, e in enumerate(r["elements"]):
            ew = f"{rw}.elements[{i}]"
            if e["code"] not in REGISTRY:
                raise ResultFormatError(
                    f"{name}: {ew}.code",
                    f"{e['code']} is not a known element code (known: {min(REGISTRY)}-{max(REGISTRY)})",
                )
            if REGISTRY[e["code"]].name != e["name"]:
                raise ResultFormatError(
                    f"{name}: {ew}.name",
                    f"expected {REGISTRY[e['code']].name!r} (element code {e['code']}), found {e['name']!r}",
                )
            genes.append(Gene(e["code"], float(e["p"])))
        out.append(Row(code, tuple(genes)))
    return ElementMatrix(tuple(inputs), tuple(out))


def parse_result(doc: Any, name: str = "result.json") -> EdmResult:
    """Validate a parsed JSON document and build an :class:`EdmResult`.

    Raises
    ------
    ResultFormatError
        Naming ``name`` and the field, with what was expected and found.
    """
    if not isinstance(doc, dict):
        raise ResultFormatError(f"{name}: (top level)",
                                f"expected a JSON object, found {json_kind(doc)}")
    for key, want in (("format", FORMAT), ("version", VERSION)):
        if key in doc and doc[key] != want:
            raise ResultFormatError(f"{name}: {key}",
                                    f"expected {json.dumps(want)}, found {json.dumps(doc[key])}")
    err = _schema_error(name, doc)
    if err is not None:
        raise err
    problem = target_name_problem(doc["target"])
    if problem:
        raise ResultFormatError(f"{name}: target", problem)
    inputs = doc["inputs"]
    ranges = {}
    for ename, rdoc in doc["parameter_ranges"].items():
        where = f"{name}: parameter_ranges.{ename}"
        try:
            ranges[ename] = check_range(ename, ParamRange(float(rdoc["low"]), float(rdoc["high"]),
                                                          rdoc["scaling"]))
        except ValueError as exc:
            raise ResultFormatError(where, str(exc)) from None
    matrix = _matrix_from_json(name, "matrix", doc["matrix"], inputs)
    for j, row in enumerate(matrix.rows):
        for i, g in enumerate(row.genes):
            el = g.element
            if el.param is not None and el.name not in ranges:
                raise ResultFormatError(
                    f"{name}: parameter_ranges.{el.name}",
                    f"expected a range for element {el.name!r} (used at rows[{j}].elements[{i}]), "
                    "found none",
                )
    steps = []
    for k, s in enumerate(doc["steps"]):
        m = _matrix_from_json(name, f"steps[{k}].matrix", s["matrix"], inputs)
        steps.append(StepRecord(
            step=s["step"], matrix=m, fitness=float(s["fitness"]),
            history=tuple(float(h) for h in s["history"]),
            generations=s.get("generations", len(s["history"])),
            evaluations=s.get("evaluations", 0), weighting=s.get("weighting", {}),
        ))
    fitness = doc.get("fitness")
    if fitness is not None and not math.isfinite(fitness):
        raise ResultFormatError(f"{name}: fitness", f"expected a finite number, found {fitness}")
    ts, length = float(doc["sample_time"]), float(doc["record_length"])
    for key, value in (("sample_time", ts), ("record_length", length)):
        if not math.isfinite(value):  # 1e999 reads as infinity
            raise ResultFormatError(f"{name}: {key}", f"expected a finite number, found {value}")
    try:
        comp = Compensator(matrix, ts, ranges, length)
    except ValueError as exc:  # the default ranges follow from both (1e-300 s, say, breaks them)
        raise ResultFormatError(f"{name}: sample_time, record_length",
                                f"expected a sample time and record length that give usable "
                                f"parameter ranges, found {ts:g} s and {length:g} s "
                                f"({exc.__cause__ or exc})") from None
    return EdmResult(comp, doc["target"], tuple(steps), dict(doc["provenance"]), fitness,
                     report_inputs=dict(doc.get("report_inputs", {})),
                     validation=dict(doc.get("validation", {})),
                     parsimony=_parsimony_from_json(name, doc, inputs),
                     axis=doc.get("axis", "rotary"), logs=_logs_from_json(name, doc),
                     physics=dict(doc.get("physics", {})))


def _logs_from_json(name: str, doc: Mapping[str, Any]) -> tuple[dict[str, Any], ...]:
    logs = doc.get("logs", [])
    for k, log in enumerate(logs):
        names = [c["name"] for c in log["columns"]]
        for i, col in enumerate(names):
            if names.index(col) != i:
                raise ResultFormatError(f"{name}: logs[{k}].columns[{i}].name",
                                        f"expected unique column names, found {col!r} twice")
        try:
            ColumnRoles({c["name"]: c["role"] for c in log["columns"] if c["role"]})
        except DataFormatError as exc:
            raise ResultFormatError(f"{name}: logs[{k}].columns", exc.problem) from None
    return tuple(dict(g) for g in logs)


def _parsimony_from_json(name: str, doc: Mapping[str, Any], inputs: Sequence[str]
                         ) -> dict[str, Any]:
    par = doc.get("parsimony")
    if not par:
        return {}
    front = par["front"]
    for k, member in enumerate(front):
        _matrix_from_json(name, f"parsimony.front[{k}].matrix", member["matrix"], inputs)
        if member["member"] != k + 1:
            raise ResultFormatError(f"{name}: parsimony.front[{k}].member",
                                    f"expected {k + 1} (members are numbered from 1), "
                                    f"found {member['member']}")
    if not 1 <= par["selected"] <= len(front):
        raise ResultFormatError(f"{name}: parsimony.selected",
                                f"expected a member number 1-{len(front)}, found {par['selected']}")
    return dict(par)


def front_member(result: EdmResult, k: int) -> EdmResult:
    """The result with member ``k`` (1-based) of its parsimony front as the model.

    Parameters
    ----------
    result : EdmResult
        A result with a ``parsimony`` front.
    k : int
        The member number, as in result.json and the report's table.

    Returns
    -------
    EdmResult
        The same result whose compensator holds that member's matrix, its
        ``fitness`` the member's training eq. 8 and ``validation`` its scores.

    Raises
    ------
    ResultFormatError
        When the result has no front or no member ``k``.
    """
    name = Path(result.source).name if result.source else "result.json"
    front = result.parsimony.get("front", []) if result.parsimony else []
    if not front:
        raise ResultFormatError(f"{name}: parsimony", "expected a front (a result of "
                                "edm abstract with pruning), found none")
    if not 1 <= k <= len(front):
        raise ResultFormatError(f"{name}: parsimony.front",
                                f"expected a member number 1-{len(front)}, found {k}")
    member = front[k - 1]
    matrix = _matrix_from_json(name, f"parsimony.front[{k - 1}].matrix", member["matrix"],
                               result.inputs)
    validation = dict(result.validation)
    if validation:
        validation.update(training=member["training"], validation=member["validation"])
    return replace(result, compensator=replace(result.compensator, matrix=matrix),
                   fitness=member["training"]["fitness"][0], validation=validation,
                   parsimony={**result.parsimony, "selected": k})


def load_result(path: str | Path) -> EdmResult:
    """Load and validate a result.json.

    Parameters
    ----------
    path : path-like
        The file.

    Returns
    -------
    EdmResult
        With ``sha256`` set to the file's digest.

    Raises
    ------
    ResultFormatError
        When the file is missing, not JSON, or not a valid edm-result.
    """
    doc, raw = read_json(path, ResultFormatError)
    path = Path(path)
    res = parse_result(doc, path.name)
    return replace(res, sha256=hashlib.sha256(raw).hexdigest(), source=str(path))
