"""The abstraction config: GA settings, hierarchical steps, ranges, a human model.

The config is a TOML file of data only (see ``docs/abstraction.md`` and
``examples/configs/``). Every key is checked: an unknown key, a wrong type or a
value out of range is refused with a :class:`~edm_sym.core.errors.ConfigError` that
names the file and the key. Without a file, :func:`default_config` gives the
default schedule: 4 elements per row and 2, 3, 4, 5 rows, Lambda = 1, each step
ending when it stops improving.
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any

from edm_sym.core.data import ColumnRoles
from edm_sym.core.elements import BY_NAME, ParamRange, check_range, default_ranges
from edm_sym.core.errors import ConfigError, DataFormatError
from edm_sym.core.fileio import read_toml
from edm_sym.core.formats import parse_names
from edm_sym.core.units import AXES
from edm_sym.engines.abstraction.fidelity import (
    FidelitySettings,
    parse_fidelity,
    parse_multi_fidelity,
)
from edm_sym.engines.abstraction.holdout import ValidationSettings, parse_validation
from edm_sym.engines.abstraction.parsimony import ParsimonySettings, parse_parsimony
from edm_sym.engines.abstraction.weighting import Weighting, parse_weighting

CONTINUE_MODES = ("no", "improving", "always")
#: The most independent searches one run may make (``searches``).
MAX_SEARCHES = 64

# name: (kind, minimum, maximum); kind "int", "float", "prob", "mode" or "names".
_GA_FIELDS: dict[str, tuple[str, float | None, float | None]] = {
    "population": ("int", 4, None),
    "elites": ("int", 1, None),
    "tournament": ("int", 1, None),
    "crossover_rate": ("prob", 0, 1),
    "row_crossover": ("prob", 0, 1),
    "shift_rate": ("prob", 0, 1),
    "shift_min": ("float", 1e-12, 1),
    "shift_max": ("float", 1e-12, 1),
    "mutation_rate": ("prob", 0, 1),
    "input_mutation_rate": ("prob", 0, 1),
    "through_rate": ("prob", 0, 1),
    "generations": ("int", 1, None),
    "continue": ("mode", None, None),
    "max_blocks": ("int", 1, None),
    "patience": ("int", 0, None),
    "min_improvement": ("float", 0, 1),
    "inherit_fraction": ("prob", 0, 1),
    "gain_fit": ("bool", None, None),
    "local_search": ("int", 0, None),
    "local_search_evaluations": ("int", 1, None),
    "restarts": ("int", 0, None),
    "reject_poles": ("bool", None, None),
    "harmonic_seeds": ("int", 0, 64),
    "stribeck_seeds": ("int", 0, 64),
    "elements": ("names", None, None),
}


@dataclass(frozen=True)
class GaSettings:
    """Settings of the genetic algorithm (Algorithm 1) for one step.

    Parameters
    ----------
    population : int
        I_num, individuals per generation.
    elites : int
        Best individuals copied unchanged into the next generation.
    tournament : int
        Tournament size of the selection (1: uniform random selection).
    crossover_rate : float
        Probability that a pair of parents exchanges a section of genes
        (element code and parameter together, Fig. 6).
    row_crossover : float
        Probability that the cut points of a crossover fall on row boundaries,
        so whole rows are exchanged.
    shift_rate : float
        Per element gene: probability of a parameter shift (Fig. 7a).
    shift_min, shift_max : float
        Range of ``|delta p|`` of a shift, drawn log-uniformly.
    mutation_rate : float
        Per element gene: probability of rewriting the element code with a
        freshly drawn ``p`` (Fig. 7b).
    input_mutation_rate : float
        Per row: probability of rewriting the input code.
    through_rate : float
        Probability that a randomly drawn element is ``through`` (keeps random
        rows short; 0 draws uniformly from the element set).
    generations : int
        G_max, generations per block.
    continue_mode : {"no", "improving", "always"}
        The ``continue`` of Algorithm 1: after a block of G_max generations,
        run another block never, while the block improved the best, or always
        (up to ``max_blocks``). Written ``continue`` in the config.
    max_blocks : int
        Upper bound on the number of blocks of a step.
    patience : int
        End the step after this many generations without improvement (0: never).
    min_improvement : float
        Relative decrease of the best fitness that counts as an improvement.
    inherit_fraction : float
        Share of the initial population seeded with the inherited rows (at
        least one individual when there is anything to inherit).
    gain_fit : bool
        Lamarckian local search: give new individuals the least-squares row
        scales where a gain-like element allows it (see
        :mod:`edm_sym.engines.abstraction.gain_fit`); False runs the plain Algorithm 1.
    local_search : int
        When the best has not improved for this many generations (and again
        every this many, and when the step would end), tune the best
        individual's parameters by least squares (see
        :mod:`edm_sym.engines.abstraction.local_search`); 0: never.
    local_search_evaluations : int
        Most individuals one local search evaluates.
    restarts : int
        When the step would end, restart it this many times from its elite:
        the elites stay, a share ``inherit_fraction`` of the population gets
        the best individual with one row drawn anew, the rest is random.
    reject_poles : bool
        Give an individual an infinite fitness when a tangent of one of its
        rows has a pole inside the range the row's input takes in the data
        (:mod:`edm_sym.engines.abstraction.poles`). Such a row fits the log
        it was found on and fails on the next; False keeps them (the paper's GA).
    harmonic_seeds : int
        When a step adds rows on a rotary axis with an angle input, this many
        inherited individuals get as their first new row one of the strongest
        angle harmonics of the inherited model's residual
        (:mod:`edm_sym.engines.abstraction.seeding`); 0: never.
    stribeck_seeds : int
        When a step adds rows with a velocity input, this many inherited
        individuals (after the harmonic ones) get as their first new row a
        ``tanh`` of the velocity fitted to the inherited model's residual: with
        the Coulomb row, a Stribeck hump (:mod:`edm_sym.engines.abstraction.seeding`);
        0: never.
    elements : tuple of str or None
        Element names the GA may use; None: every registered element.
    """

    population: int = 64
    elites: int = 2
    tournament: int = 3
    crossover_rate: float = 0.8
    row_crossover: float = 0.5
    shift_rate: float = 0.2
    shift_min: float = 1e-5
    shift_max: float = 0.05
    mutation_rate: float = 0.04
    input_mutation_rate: float = 0.04
    through_rate: float = 0.3
    generations: int = 50
    continue_mode: str = "improving"
    max_blocks: int = 20
    patience: int = 40
    min_improvement: float = 1e-6
    inherit_fraction: float = 0.25
    gain_fit: bool = True
    local_search: int = 20
    local_search_evaluations: int = 300
    restarts: int = 0
    reject_poles: bool = True
    harmonic_seeds: int = 3
    stribeck_seeds: int = 2
    elements: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        if self.elements is not None:
            object.__setattr__(self, "elements", tuple(self.elements))
        for f in fields(self):
            key = "continue" if f.name == "continue_mode" else f.name
            _check_value(f"GaSettings.{f.name}", key, getattr(self, f.name))
        _cross_check("GaSettings", {f.name: getattr(self, f.name) for f in fields(self)})

    def to_json(self) -> dict[str, Any]:
        """The settings as a config table (``continue`` spelled as in the file)."""
        out = {("continue" if f.name == "continue_mode" else f.name): getattr(self, f.name)
               for f in fields(self)}
        out["elements"] = list(self.elements) if self.elements is not None else None
        return out


@dataclass(frozen=True)
class StepConfig:
    """One hierarchical step (paper, Figs. 8 and 19).

    Parameters
    ----------
    n_rows : int
        m, rows of the element matrix (>= the previous step's).
    n_elements : int
        n, elements per row (>= the previous step's).
    weighting : Weighting
        Lambda(q) of eq. 8 for this step.
    ga : GaSettings
        The genetic algorithm's settings for this step.
    """

    n_rows: int
    n_elements: int = 4
    weighting: Weighting = field(default_factory=Weighting)
    ga: GaSettings = field(default_factory=GaSettings)

    def __post_init__(self) -> None:
        for name in ("n_rows", "n_elements"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise ConfigError(f"StepConfig.{name}", f"expected an integer >= 1, found {v!r}")


@dataclass(frozen=True)
class InitialRow:
    """A row of the human model that seeds the first step.

    Parameters
    ----------
    input : str
        The input column this row reads.
    elements : tuple of (name, value or None)
        Elements left to right with their decoded parameter values ``a``
        (None for parameter-free elements); encoded into ``p`` by the ranges.
    """

    input: str
    elements: tuple[tuple[str, float | None], ...]


@dataclass(frozen=True)
class AbstractionConfig:
    """Everything an abstraction run is told (frozen; see :func:`load_config`).

    Parameters
    ----------
    steps : tuple of StepConfig
        The hierarchical schedule, run in order.
    ranges : mapping of element name to partial range
        Overrides of the default parameter ranges: ``{"gain": {"low": -2.0,
        "high": 2.0}}``; missing bounds or scaling keep the default.
    initial : tuple of InitialRow
        A human model seeding step 1 (empty: none).
    cache_mb : float
        Memory bound of the row-output cache [MB].
    validation : ValidationSettings
        What is held out from the GA (``[validation]``; default: the last 20 %).
    parsimony : ParsimonySettings
        The pruning pass after the search and the front's selection rule.
    source : str
        The config file name (for messages).
    columns : ColumnRoles or None
        The log's columns and their roles (``[columns]``: ``qm = "position"``;
        docs/data.md#columns-and-roles); ``--time-column`` and ``--role`` go over them.
    axis : str or None
        ``"rotary"`` or ``"linear"`` (the top-level ``axis`` key); None: rotary
        unless ``--axis`` says otherwise.
    searches : int
        Independent searches of the whole schedule (the top-level ``searches``
        key, default 1), each from its own seed, run side by side on the
        workers; the search's model is chosen among the step bests of all of
        them (docs/abstraction.md#independent-searches).
    column_names : tuple of str or None
        The names of the columns of a matrix selected as ``FILE.mat:VAR``
        (``column_names``; ``--columns`` goes over it).
    data : tuple of str
        The logs (``data = ["a.csv", "b.csv"]``, paths relative to the config
        file): abstracted together when the command line names none.
    fidelity : str
        ``"full"``: every individual scored on every training sample (Algorithm
        1); ``"multi"``: ranked on windows of the log, the few that may enter
        the elite scored on all of it; ``"auto"`` (default): ``"multi"`` above
        :data:`~edm_sym.engines.abstraction.fidelity.AUTO_SAMPLES` training
        samples, else ``"full"`` (docs/abstraction.md#multi-fidelity-evaluation).
    multi_fidelity : FidelitySettings
        The windows and the promotion rule of ``"multi"`` (``[multi_fidelity]``).
    """

    steps: tuple[StepConfig, ...] = ()
    ranges: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    initial: tuple[InitialRow, ...] = ()
    cache_mb: float = 256.0
    source: str = "<default config>"
    validation: ValidationSettings = field(default_factory=ValidationSettings)
    parsimony: ParsimonySettings = field(default_factory=ParsimonySettings)
    columns: ColumnRoles | None = None
    axis: str | None = None
    searches: int = 1
    column_names: tuple[str, ...] | None = None
    data: tuple[str, ...] = ()
    fidelity: str = "auto"
    multi_fidelity: FidelitySettings = field(default_factory=FidelitySettings)

    def __post_init__(self) -> None:
        parse_fidelity(f"{self.source}: fidelity", self.fidelity)
        if not isinstance(self.multi_fidelity, FidelitySettings):
            raise ConfigError(f"{self.source}: multi_fidelity", "expected FidelitySettings, found "
                                                                f"{_found(self.multi_fidelity)}")
        if (isinstance(self.searches, bool) or not isinstance(self.searches, int)
                or not 1 <= self.searches <= MAX_SEARCHES):
            raise ConfigError(f"{self.source}: searches", f"expected an integer from 1 to "
                                                          f"{MAX_SEARCHES}, found {_found(self.searches)}")
        if self.axis is not None and (not isinstance(self.axis, str) or self.axis not in AXES):
            raise ConfigError(f"{self.source}: axis",
                              f"expected {' or '.join(AXES)}, found {_found(self.axis)}")
        steps = tuple(self.steps) or default_steps()
        object.__setattr__(self, "steps", steps)
        object.__setattr__(self, "initial", tuple(self.initial))
        for k in range(1, len(steps)):
            for name in ("n_rows", "n_elements"):
                prev, cur = getattr(steps[k - 1], name), getattr(steps[k], name)
                if cur < prev:
                    raise ConfigError(
                        f"{self.source}: step[{k}].{name}",
                        f"expected >= {prev} (step[{k - 1}]; a step inherits every row of the "
                        f"previous one), found {cur}",
                    )
        if len(self.initial) > steps[0].n_rows:
            raise ConfigError(f"{self.source}: initial.rows",
                              f"expected at most {steps[0].n_rows} rows (step[0].n_rows), "
                              f"found {len(self.initial)}")
        for j, row in enumerate(self.initial):
            if len(row.elements) > steps[0].n_elements:
                raise ConfigError(f"{self.source}: initial.rows[{j}].elements",
                                  f"expected at most {steps[0].n_elements} elements "
                                  f"(step[0].n_elements), found {len(row.elements)}")

    def resolve_ranges(self, ts: float, t_sum: float) -> dict[str, ParamRange]:
        """Default ranges for Ts and T_sum with this config's overrides applied.

        Raises
        ------
        ConfigError
            When an override makes an unusable range (low >= high, log with low <= 0).
        """
        out = default_ranges(ts, t_sum)
        for name, over in sorted(self.ranges.items()):
            base = out[name]
            kw = {"low": base.low, "high": base.high, "scaling": base.scaling, **over}
            try:
                out[name] = check_range(name, ParamRange(float(kw["low"]), float(kw["high"]),
                                                         kw["scaling"]))
            except ValueError as exc:
                raise ConfigError(f"{self.source}: ranges.{name}", str(exc)) from None
        return out

    def to_json(self) -> dict[str, Any]:
        """A canonical JSON-able form (for checkpoint fingerprints)."""
        return {
            "steps": [{"n_rows": s.n_rows, "n_elements": s.n_elements,
                       "weighting": s.weighting.to_json(), "ga": s.ga.to_json()}
                      for s in self.steps],
            "ranges": {k: dict(v) for k, v in sorted(self.ranges.items())},
            "initial": [{"input": r.input, "elements": [list(e) for e in r.elements]}
                        for r in self.initial],
            # Not the parsimony settings: they act after the search, a checkpoint needs none.
            "validation": self.validation.to_json(),
            # Only when set: the fingerprints of runs that do not set them stay as they were.
            **({"fidelity": self.fidelity} if self.fidelity != "auto" else {}),
            **({"multi_fidelity": self.multi_fidelity.to_json()}
               if self.multi_fidelity != FidelitySettings() else {}),
        }

    def digest(self) -> str:
        """sha256 of :meth:`to_json` (what the run depends on)."""
        text = json.dumps(self.to_json(), sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()


def default_steps(ga: GaSettings | None = None) -> tuple[StepConfig, ...]:
    """The default schedule: 4 elements per row; 2, 3, 4, 5 rows; Lambda = 1."""
    ga = ga or GaSettings()
    return tuple(StepConfig(n_rows=m, n_elements=4, ga=ga) for m in (2, 3, 4, 5))


def default_config() -> AbstractionConfig:
    """The configuration used when no file is given (see :func:`default_steps`)."""
    return AbstractionConfig()


# -- validation ---------------------------------------------------------------

def _type_name(value: Any) -> str:
    return {bool: "boolean", int: "integer", float: "float", str: "string",
            list: "array", dict: "table"}.get(type(value), type(value).__name__)


def _found(value: Any) -> str:
    text = json.dumps(value, default=str) if not isinstance(value, str) else repr(value)
    text = text if len(text) <= 40 else text[:37] + "..."
    return f"{_type_name(value)} {text}"


def _check_value(where: str, key: str, value: Any) -> Any:
    kind, lo, hi = _GA_FIELDS[key]
    if kind == "int":
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(where, f"expected an integer, found {_found(value)}")
    elif kind in ("float", "prob"):
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ConfigError(where, f"expected a number, found {_found(value)}")
        if not math.isfinite(value):
            raise ConfigError(where, f"expected a finite number, found {value}")
        value = float(value)
    elif kind == "bool":
        if not isinstance(value, bool):
            raise ConfigError(where, f"expected true or false, found {_found(value)}")
        return value
    elif kind == "mode":
        if value not in CONTINUE_MODES:
            raise ConfigError(where, f"expected one of {', '.join(map(repr, CONTINUE_MODES))}, "
                                     f"found {_found(value)}")
        return value
    else:  # names
        if value is None:
            return None
        if not isinstance(value, list | tuple) or not value:
            raise ConfigError(where, f"expected a non-empty array of element names, "
                                     f"found {_found(value)}")
        for k, name in enumerate(value):
            if not isinstance(name, str) or name not in BY_NAME:
                raise ConfigError(f"{where}[{k}]", f"expected an element name (known: "
                                                   f"{', '.join(BY_NAME)}), found {_found(name)}")
            if list(value).index(name) != k:
                raise ConfigError(f"{where}[{k}]", f"expected each name once, found {name!r} again")
        return tuple(value)
    if lo is not None and value < lo:
        raise ConfigError(where, f"expected a value >= {lo:g}, found {value}")
    if hi is not None and value > hi:
        raise ConfigError(where, f"expected a value <= {hi:g}, found {value}")
    return value


def _cross_check(where: str, ga: Mapping[str, Any]) -> None:
    if ga["elites"] >= ga["population"]:
        raise ConfigError(f"{where}.elites", f"expected fewer than population "
                                             f"({ga['population']}), found {ga['elites']}")
    if ga["tournament"] > ga["population"]:
        raise ConfigError(f"{where}.tournament", f"expected at most population "
                                                 f"({ga['population']}), found {ga['tournament']}")
    if ga["shift_min"] > ga["shift_max"]:
        raise ConfigError(f"{where}.shift_min", f"expected <= shift_max ({ga['shift_max']}), "
                                                f"found {ga['shift_min']}")


def _unknown(where: str, table: Mapping[str, Any], known: Any) -> None:
    for key in table:
        if key not in known:
            raise ConfigError(f"{where}.{key}" if where else key,
                              f"unknown key (known: {', '.join(known)})")


def _table(where: str, value: Any) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        raise ConfigError(where, f"expected a table, found {_found(value)}")
    return value


def _ga_settings(where: str, table: Mapping[str, Any], base: GaSettings) -> GaSettings:
    kw = {}
    for key, value in table.items():
        name = "continue_mode" if key == "continue" else key
        kw[name] = _check_value(f"{where}.{key}", key, value)
    _cross_check(where, {**{f.name: getattr(base, f.name) for f in fields(base)}, **kw})
    return replace(base, **kw) if kw else base


_TOP_KEYS = ("cache_mb", "ga", "ranges", "initial", "step", "validation",
             "parsimony", "columns", "axis", "searches", "column_names", "data",
             "fidelity", "multi_fidelity")
_STEP_KEYS = ("n_rows", "n_elements", "weighting", *_GA_FIELDS)


def parse_config(doc: Mapping[str, Any], source: str = "config.toml") -> AbstractionConfig:
    """Build an :class:`AbstractionConfig` from a parsed TOML document.

    Parameters
    ----------
    doc : mapping
        The parsed TOML (see ``docs/abstraction.md`` for the keys).
    source : str
        The file name, for messages.

    Returns
    -------
    AbstractionConfig

    Raises
    ------
    ConfigError
        Naming ``source`` and the key, with what was expected and found.
    """
    f = f"{source}: "
    for key in doc:
        if key not in _TOP_KEYS:
            raise ConfigError(f"{source}: {key}", f"unknown key (known: {', '.join(_TOP_KEYS)})")
    cache_mb = 256.0
    if "cache_mb" in doc:
        v = doc["cache_mb"]
        if isinstance(v, bool) or not isinstance(v, int | float) or not 0 < v < 1e6:
            raise ConfigError(f"{f}cache_mb", f"expected a number > 0 and < 1e6 (MB), found {_found(v)}")
        cache_mb = float(v)
    ga = GaSettings()
    if "ga" in doc:
        table = _table(f"{f}ga", doc["ga"])
        _unknown(f"{f}ga", table, _GA_FIELDS)
        ga = _ga_settings(f"{f}ga", table, ga)
    ranges = _parse_ranges(f, doc.get("ranges", {}))
    steps = []
    raw_steps = doc.get("step", [])
    if not isinstance(raw_steps, list):
        raise ConfigError(f"{f}step", f"expected an array of tables [[step]], found "
                                      f"{_found(raw_steps)}")
    if "step" in doc and not raw_steps:
        # Not the default schedule in silence: the file asked for steps and gave none.
        raise ConfigError(f"{f}step", "expected at least one [[step]] table (leave `step` out "
                                      "for the default schedule), found an empty array")
    for k, s in enumerate(raw_steps):
        where = f"{f}step[{k}]"
        s = _table(where, s)
        _unknown(where, s, _STEP_KEYS)
        if "n_rows" not in s:
            raise ConfigError(f"{where}.n_rows", "expected the number of rows, found it missing")
        dims = {}
        for name in ("n_rows", "n_elements"):
            if name in s:
                v = s[name]
                if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                    raise ConfigError(f"{where}.{name}", f"expected an integer >= 1, found "
                                                         f"{_found(v)}")
                dims[name] = v
        weighting = (parse_weighting(f"{where}.weighting", s["weighting"])
                     if "weighting" in s else Weighting())
        step_ga = _ga_settings(where, {k2: v for k2, v in s.items() if k2 in _GA_FIELDS}, ga)
        steps.append(StepConfig(weighting=weighting, ga=step_ga, **dims))
    if not steps:
        steps = list(default_steps(ga))
    initial = _parse_initial(f, doc.get("initial"))
    validation = parse_validation(f"{f}validation", doc.get("validation", {}))
    parsimony = parse_parsimony(f"{f}parsimony", doc.get("parsimony", {}))
    columns = None
    if "columns" in doc:
        try:
            columns = ColumnRoles.from_table(f"{f}columns", doc["columns"])
        except DataFormatError as exc:
            raise ConfigError(exc.where, exc.problem) from None
    names = None
    if "column_names" in doc:
        try:
            names = parse_names(doc["column_names"], f"{f}column_names")
        except DataFormatError as exc:
            raise ConfigError(exc.where, exc.problem) from None
    logs = doc.get("data", [])
    if isinstance(logs, str):
        logs = [logs]
    if not isinstance(logs, list) or not all(isinstance(d, str) and d.strip() for d in logs):
        raise ConfigError(f"{f}data", f"expected a list of log files, found {_found(logs)}")
    fidelity = parse_fidelity(f"{f}fidelity", doc.get("fidelity", "auto"))
    multi = parse_multi_fidelity(f"{f}multi_fidelity", doc.get("multi_fidelity", {}))
    return AbstractionConfig(tuple(steps), ranges, initial, cache_mb, source, validation,
                             parsimony, columns, doc.get("axis"), doc.get("searches", 1),
                             names, tuple(logs), fidelity, multi)


def _parse_ranges(f: str, doc: Any) -> dict[str, dict[str, Any]]:
    out: dict[str, dict[str, Any]] = {}
    for name, rdoc in _table(f"{f}ranges", doc).items():
        where = f"{f}ranges.{name}"
        el = BY_NAME.get(name)
        if el is None:
            raise ConfigError(where, f"expected an element name (known: {', '.join(BY_NAME)})")
        if el.param is None:
            raise ConfigError(where, f"element {name!r} has no parameter, so no range")
        rdoc = _table(where, rdoc)
        _unknown(where, rdoc, ("low", "high", "scaling"))
        over: dict[str, Any] = {}
        for key in ("low", "high"):
            if key in rdoc:
                v = rdoc[key]
                if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
                    raise ConfigError(f"{where}.{key}", f"expected a finite number, found "
                                                        f"{_found(v)}")
                over[key] = float(v)
        if "scaling" in rdoc:
            if rdoc["scaling"] not in ("linear", "log"):
                raise ConfigError(f"{where}.scaling", f"expected 'linear' or 'log', found "
                                                      f"{_found(rdoc['scaling'])}")
            over["scaling"] = rdoc["scaling"]
        if "low" in over and "high" in over and not over["low"] < over["high"]:
            raise ConfigError(where, f"expected low < high, found [{over['low']}, {over['high']}]")
        if over.get("scaling") == "log" and over.get("low", 1.0) <= 0:
            raise ConfigError(f"{where}.low", f"a log scaling needs low > 0, found {over['low']}")
        out[name] = over
    return out


def _parse_initial(f: str, doc: Any) -> tuple[InitialRow, ...]:
    if doc is None:
        return ()
    doc = _table(f"{f}initial", doc)
    _unknown(f"{f}initial", doc, ("rows",))
    rows = doc.get("rows", [])
    if not isinstance(rows, list):
        raise ConfigError(f"{f}initial.rows", f"expected an array of rows, found {_found(rows)}")
    out = []
    for j, r in enumerate(rows):
        where = f"{f}initial.rows[{j}]"
        r = _table(where, r)
        _unknown(where, r, ("input", "elements"))
        if not isinstance(r.get("input"), str):
            raise ConfigError(f"{where}.input", f"expected an input column name, found "
                                                f"{_found(r.get('input'))}")
        els = r.get("elements")
        if not isinstance(els, list) or not els:
            raise ConfigError(f"{where}.elements", f"expected a non-empty array of "
                                                   f"[name, value] pairs, found {_found(els)}")
        genes: list[tuple[str, float | None]] = []
        for i, e in enumerate(els):
            ew = f"{where}.elements[{i}]"
            pair = [e] if isinstance(e, str) else e
            if not isinstance(pair, list) or not 1 <= len(pair) <= 2 or not isinstance(pair[0], str):
                raise ConfigError(ew, f"expected [name, value] or a name, found {_found(e)}")
            name = pair[0]
            el = BY_NAME.get(name)
            if el is None:
                raise ConfigError(ew, f"expected an element name (known: {', '.join(BY_NAME)}), "
                                      f"found {name!r}")
            if el.param is None:
                if len(pair) == 2:  # a value it would silently drop
                    raise ConfigError(ew, f"expected [{name!r}] (element {name!r} has no "
                                          f"parameter), found the value {_found(pair[1])}")
                genes.append((name, None))
                continue
            if len(pair) != 2:
                raise ConfigError(ew, f"expected [{name!r}, value] (element {name!r} has a "
                                      f"parameter: {el.param.meaning}), found no value")
            v = pair[1]
            if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
                raise ConfigError(ew, f"expected a finite value, found {_found(v)}")
            genes.append((name, float(v)))
        out.append(InitialRow(r["input"], tuple(genes)))
    return tuple(out)


def load_config(path: str | Path) -> AbstractionConfig:
    """Read and validate an abstraction config (TOML, data only).

    Parameters
    ----------
    path : path-like
        The TOML file.

    Returns
    -------
    AbstractionConfig

    Raises
    ------
    ConfigError
        When the file is missing, is not TOML, or has an unknown key, a wrong
        type or a value out of range (the message names the file and key).
    """
    path = Path(path)
    doc = read_toml(path, ConfigError)
    return parse_config(doc, path.name)


def inherit(cfg: AbstractionConfig, previous: Any, *, inputs: Sequence[str], axis: str, ts: float,
            t_sum: float, where: str = "--initial") -> AbstractionConfig:
    """The schedule continued from a previous result's rows (the paper's inheritance).

    The previous model's rows seed the first step large enough to hold them
    (the steps before it are left out: the hierarchy continues where the
    previous abstraction ended); its parameter values keep their meaning
    (``a``, decoded), clipped into this run's ranges.

    Parameters
    ----------
    cfg : AbstractionConfig
    previous : EdmResult
        The previous result (its ``sha256`` is what the new one records).
    inputs, axis, ts
        This run's inputs, axis and sample time, which must be the previous one's.
    t_sum : float
        This run's record length [s] (its ranges clip the values).
    where : str
        For messages (the option or key that named the file).

    Raises
    ------
    ConfigError
        Another axis, other inputs or another sample time (beyond 0.1 %), or a
        schedule with no step as large as the previous matrix.
    """
    name = f"{where} {Path(previous.source).name if previous.source else 'result'}"
    prev_axis = previous.axis or "rotary"
    if prev_axis != axis:
        raise ConfigError(name, f"expected a result of the {axis} axis, found one of the "
                                f"{prev_axis} axis (its units differ)")
    prev_inputs = tuple(previous.compensator.matrix.inputs)
    if prev_inputs != tuple(inputs):
        raise ConfigError(name, f"expected the inputs {', '.join(inputs)}, found "
                                f"{', '.join(prev_inputs)} (its rows read them by position)")
    prev_ts = float(previous.compensator.sample_time)
    if abs(prev_ts - ts) > 1e-3 * ts:
        raise ConfigError(name, f"expected the sample time {ts:g} s of the logs, found {prev_ts:g} s "
                                "(its filters and delays are discretised at it)")
    comp = previous.compensator
    rows = []
    for row in comp.matrix.rows:
        genes = list(row.genes)
        while len(genes) > 1 and genes[-1].element.is_identity:
            genes.pop()
        elements = [(g.element.name, comp.value(g)) for g in genes]
        rows.append(InitialRow(prev_inputs[row.input], tuple(elements)))
    m, n = len(rows), max(len(r.elements) for r in rows)
    first = next((k for k, s in enumerate(cfg.steps) if s.n_rows >= m and s.n_elements >= n), None)
    if first is None:
        largest = cfg.steps[-1]
        raise ConfigError(name, f"expected a step of the schedule with at least {m} rows of {n} "
                                f"elements to continue from, found at most {largest.n_rows}x"
                                f"{largest.n_elements}; add a larger [[step]]")
    ranges = cfg.resolve_ranges(ts, t_sum)
    clipped = []
    for r in rows:
        els = []
        for el, a in r.elements:
            if a is not None:
                rng = ranges[el]
                a = min(max(a, rng.low), rng.high)
            els.append((el, a))
        clipped.append(InitialRow(r.input, tuple(els)))
    return replace(cfg, steps=cfg.steps[first:], initial=tuple(clipped))
