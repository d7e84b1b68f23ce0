"""Data logs: CSV, .npz and MATLAB .mat (docs/cli.md#data-files).

A log is a set of equally long numeric columns with a uniform sample time.
Every defect (missing file or column, empty file, non-numeric cell, NaN or
Inf, non-uniform time) is refused with a :class:`~edm_sym.core.errors.DataFormatError`
that names the file and the row or column.
"""

from __future__ import annotations

import contextlib
import csv
import hashlib
import io
import math
import numbers
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from edm_sym.core import budget
from edm_sym.core.errors import DataFormatError
from edm_sym.core.fileio import write_atomic
from edm_sym.core.formats import (
    SELECTABLE,
    contents,
    describe,
    is_matrix,
    parse_names,
    read_tree,
    select,
    selection_hint,
    split_spec,
)

#: Clock drift accepted between two sample times of one drive (relative): a log's
#: time column and ``--ts``, or a model's sample time and a second log's
#: (docs/data.md, "Sample time").
TIME_RTOL = 1e-3
#: A smaller relative difference of two sample times is the rounding of a time column's
#: steps, not drift: it is accepted without a note.
TIME_ROUNDING = 1e-12
#: Jitter accepted on single time stamps: every step within this share of the
#: median step. A longer step is a gap (missing samples), a shorter one a burst.
JITTER_RTOL = 0.25
#: The sample times a log may have [s]: from a 1 GHz clock to a sample every
#: 17 minutes. Beyond them the element ranges of eqs. 6-7 and the
#: LuGre model's scales leave what a double holds (docs/data.md, "Sample time").
TS_RANGE = (1e-9, 1e3)
#: A data spec ``plant:PRESET/EXCITATION[@SEED]`` names a simulated plant log.
PLANT_SCHEME = "plant:"


#: The time column when no other is named (``--time-column``, a ``time`` role).
DEFAULT_TIME = "t"
#: What a column of a log may be (docs/data.md#columns-and-roles).
LOG_ROLES = ("time", "target", "position", "position_wrapped", "velocity", "acceleration", "input")
#: Roles at most one column has.
UNIQUE_ROLES = ("time", "target")
#: Roles of the signals a compensator row may take as its input; ``input`` has no
#: physical role (its terms stay unclassified).
INPUT_ROLES = ("position", "position_wrapped", "velocity", "acceleration", "input")


def is_plant_spec(spec: object) -> bool:
    """True for a ``plant:PRESET/EXCITATION[@SEED]`` data spec."""
    return isinstance(spec, str) and spec.startswith(PLANT_SCHEME)


@dataclass(frozen=True)
class ColumnRoles:
    """Which column of a log is what: column name -> one of :data:`LOG_ROLES`.

    Given by ``--time-column`` and ``--role COL=ROLE`` (:meth:`parse`), a
    ``[columns]`` table of a TOML file (:meth:`from_table`), or recorded in a
    result (``EdmResult.column_roles``). ``time`` and ``target`` name one
    column at most; several columns may share a motion role (two velocities).

    Parameters
    ----------
    roles : mapping of str to str
        Column -> role, in the order given.
    where : str
        Where they were given, for messages: the parameter (``"roles"``), a
        command's option (``"--role"``) or a table (``"cfg.toml: columns"``).
    loose : frozenset of str
        Columns whose role applies only when a log has them: the roles a model
        file records (a second log of the axis may lack its target); the
        columns given by options and tables must all be present.

    Raises
    ------
    DataFormatError
        An unknown role, or ``time``/``target`` given to two columns.
    """

    roles: Mapping[str, str] = field(default_factory=dict)
    where: str = "roles"
    loose: frozenset[str] = frozenset()

    def __post_init__(self) -> None:
        seen: dict[str, str] = {}
        for col, role in self.roles.items():
            if role not in LOG_ROLES:
                raise DataFormatError(_at(self.where, col),
                                      f"expected a role of {', '.join(LOG_ROLES)}, found {role!r}")
            if role in UNIQUE_ROLES and role in seen:
                raise DataFormatError(_at(self.where, col),
                                      f"expected one column with the role {role!r}, found it given "
                                      f"twice ({seen[role]!r} and {col!r})")
            seen.setdefault(role, col)
        object.__setattr__(self, "roles", dict(self.roles))
        object.__setattr__(self, "loose", frozenset(self.loose) & set(self.roles))

    @classmethod
    def parse(cls, items: Iterable[str] = (), *, time_column: str | None = None,
              where: str = "roles") -> ColumnRoles:
        """Roles from ``COL=ROLE`` strings (``--role``) and a ``time_column`` (``--time-column``).

        ``where`` names them in messages (a command passes ``"--role"``).

        Raises
        ------
        DataFormatError
            A string without ``=``, an unknown role, a column given twice, or
            a second time or target column.
        """
        roles: dict[str, str] = {}
        if time_column is not None:
            if not time_column.strip():
                raise DataFormatError("time_column", "expected a column name, found nothing")
            roles[time_column.strip()] = "time"
        for item in items:
            col, sep, role = str(item).rpartition("=")
            col, role = col.strip(), role.strip()
            if not sep or not col:
                raise DataFormatError(where, f"expected COL=ROLE (a role of {', '.join(LOG_ROLES)}), "
                                      f"found {item!r}")
            _add_role(roles, col, role, where)
        return cls(roles, where)

    @classmethod
    def from_table(cls, where: str, table: object) -> ColumnRoles:
        """Roles from a TOML ``[columns]`` table: ``qm = "position"``, ``t = "time"``.

        Raises
        ------
        DataFormatError
            A table that is no table of strings, or roles as for :meth:`parse`.
        """
        if not isinstance(table, Mapping):
            raise DataFormatError(where, f"expected a table of COLUMN = \"ROLE\", found {table!r}")
        roles: dict[str, str] = {}
        for col, role in table.items():
            if not isinstance(role, str):
                raise DataFormatError(_at(where, col),
                                      f"expected a role of {', '.join(LOG_ROLES)}, found {role!r}")
            _add_role(roles, col, role, where)
        return cls(roles, where)

    def over(self, base: ColumnRoles | None) -> ColumnRoles:
        """These roles over ``base`` (options over a config file): a column or a
        ``time``/``target`` role given here replaces base's."""
        if base is None:
            return self
        mine = set(self.roles.values()) & set(UNIQUE_ROLES)
        kept = {c: r for c, r in base.roles.items() if c not in self.roles and r not in mine}
        where = self.where if not kept else base.where if not self.roles else (
            f"{self.where} or {base.where}")
        return ColumnRoles({**kept, **self.roles}, where, (base.loose & set(kept)) | self.loose)

    def with_role(self, column: str, role: str) -> ColumnRoles:
        """These roles and ``column``'s (a ``--target``), which must not contradict them."""
        have = self.roles.get(column)
        if have == role:
            return self
        if have is not None:
            raise DataFormatError(_at(self.where, column),
                                  f"expected one role per column, found {have!r} and {role!r}")
        other = self.column_of(role) if role in UNIQUE_ROLES else None
        if other is not None:
            raise DataFormatError(_at(self.where, other),
                                  f"expected the {role} column {column!r}, found {other!r} given "
                                  f"the role {role!r}")
        return ColumnRoles({**self.roles, column: role}, self.where, self.loose)

    def column_of(self, role: str) -> str | None:
        """The (first) column with ``role``, or None."""
        return next((c for c, r in self.roles.items() if r == role), None)

    @property
    def time(self) -> str | None:
        """The time column named, or None (then ``t`` when the log has it)."""
        return self.column_of("time")

    @property
    def target(self) -> str | None:
        """The target column named, or None."""
        return self.column_of("target")

    @property
    def inputs(self) -> tuple[str, ...]:
        """The columns with an input role (:data:`INPUT_ROLES`), in the order given."""
        return tuple(c for c, r in self.roles.items() if r in INPUT_ROLES)


def _at(where: str, col: str) -> str:
    """``--role qm`` for an option, ``roles['qm']`` for a parameter, ``cfg.toml: columns.qm``
    for a table."""
    if where.startswith("--"):
        return f"{where} {col}"
    return f"{where}[{col!r}]" if where.isidentifier() else f"{where}.{col}"


def _add_role(roles: dict[str, str], col: str, role: str, where: str) -> None:
    if col in roles:
        raise DataFormatError(_at(where, col), f"expected one role per column, found "
                              f"{roles[col]!r} and {role!r}")
    roles[col] = role


@dataclass(frozen=True)
class DataLog:
    """A uniformly sampled log.

    Parameters
    ----------
    columns : mapping of str to numpy.ndarray
        Equally long float columns, in file order.
    ts : float
        Sample time [s].
    source : str
        The file name (for messages).
    sha256 : str
        Digest of the file's bytes (provenance).
    scalars : mapping of str to float
        Scalar values stored beside the columns (.mat and .npz files).
    roles : mapping of str to str
        The roles the columns were given (:class:`ColumnRoles`), the time
        column's among them; empty when none were.
    note : str
        What the file holds beside the columns and how to select it, added to
        the message of a missing column (a matrix or struct of a .mat file).
    decimation : int
        The factor the file's samples were decimated by (:func:`decimate`;
        1: as read), recorded in the provenance.
    """

    columns: Mapping[str, np.ndarray]
    ts: float
    source: str = "<memory>"
    sha256: str | None = None
    scalars: Mapping[str, float] = field(default_factory=dict)
    roles: Mapping[str, str] = field(default_factory=dict)
    note: str = field(default="", compare=False)
    decimation: int = 1

    def __post_init__(self) -> None:
        # A log made in memory gets the checks a file gets as it is read: at least one
        # column, all of one length (one dimension each), a positive sample time.
        if not self.columns:
            raise DataFormatError(f"{self.source}: columns", "expected at least one column, "
                                                             "found none")
        lengths = {}
        for name, col in self.columns.items():
            shape = np.shape(col)
            if len(shape) != 1:
                raise DataFormatError(f"{self.source}: column {name!r}",
                                      f"expected a column of one dimension, found shape {shape}")
            lengths[name] = shape[0]
        first, n = next(iter(lengths.items()))
        other = next((c for c, k in lengths.items() if k != n), None)
        if other is not None:
            raise DataFormatError(f"{self.source}: column {other!r}",
                                  f"expected {n} rows as column {first!r} has, "
                                  f"found {lengths[other]}")
        ts = self.ts
        if isinstance(ts, bool) or not isinstance(ts, numbers.Real) \
                or not (math.isfinite(ts) and ts > 0):
            raise DataFormatError(f"{self.source}: sample time",
                                  f"expected a positive finite number of seconds, found {ts!r}")

    def __len__(self) -> int:
        return len(next(iter(self.columns.values())))

    @property
    def time_column(self) -> str | None:
        """The time column: the one with the role ``time``, else ``t`` when present, else None."""
        named = next((c for c, r in self.roles.items() if r == "time"), None)
        if named is not None:
            return named
        return DEFAULT_TIME if DEFAULT_TIME in self.columns else None

    @property
    def times(self) -> np.ndarray:
        """The time stamps [s]: the time column, or ``k Ts`` for a log without one."""
        name = self.time_column
        if name is not None:
            return np.asarray(self.columns[name], dtype=float)
        return np.arange(len(self)) * self.ts

    def role_of(self, name: str) -> str | None:
        """The role of a column: given, ``time`` for the time column, else None."""
        if name == self.time_column:
            return "time"
        return self.roles.get(name)

    def record(self, use: str) -> dict[str, object]:
        """Provenance of this log in a result (result.json ``logs[]``).

        Parameters
        ----------
        use : str
            What the log was used for: ``"abstraction"`` or ``"validation"``.

        Each column is recorded with its role and its smallest and largest
        value, which the exports give as an input's expected range.
        """
        out = {"use": use, "file": self.source, "sha256": self.sha256, "rows": len(self),
               "sample_time": float(self.ts),
               "columns": [{"name": c, "role": self.role_of(c), "min": float(np.min(v)),
                            "max": float(np.max(v))} for c, v in self.columns.items()]}
        if self.decimation > 1:
            out["decimate"] = {"factor": self.decimation, "filter": DECIMATE_FILTER}
        return out

    def require_varying(self, names: Iterable[str]) -> None:
        """Refuse an input among ``names`` that says nothing about the axis.

        A constant column carries no information; the log's time column is the
        clock, not the axis (a compensator of it does not carry to another run).

        Raises
        ------
        DataFormatError
            Naming the file, the column and its rows.
        """
        for name in names:
            if name == self.time_column:
                raise DataFormatError(f"{self.source}: column {name!r}",
                                      "expected a signal of the axis for an input, found the "
                                      "log's time column (a model of the clock does not carry "
                                      "to another run)")
            col = self.column(name, role="input column")
            if len(col) and np.all(col == col[0]):
                raise DataFormatError(f"{self.source}: column {name!r}",
                                      f"expected a varying signal for an input, found "
                                      f"{col[0]:g} on all {len(col)} rows")

    @contextlib.contextmanager
    def naming(self, **arguments: str) -> Iterator[None]:
        """A ``DataFormatError`` about an argument taken from this log names its file and column.

        ``with log.naming(velocity="omega"): identify_lugre(...)``: the function
        refuses its ``velocity`` argument; the message then says
        ``log.csv: column 'omega'``.
        """
        try:
            yield
        except DataFormatError as exc:
            if exc.where not in arguments:
                raise
            raise DataFormatError(f"{self.source}: column {arguments[exc.where]!r}",
                                  exc.problem) from None

    def require_finite(self, names: Iterable[str]) -> None:
        """Refuse NaN or an infinity in the columns ``names`` (naming the first, by row).

        Logs read from files are checked as they are read; this is for logs
        made in memory (``DataLog(columns, ts)``).

        Raises
        ------
        DataFormatError
            Naming the log, the row and the column.
        """
        for name in names:
            col = self.column(name)
            bad = np.flatnonzero(~np.isfinite(col))
            if bad.size:
                raise DataFormatError(f"{self.source}: row {bad[0] + 1}, column {name!r}",
                                      f"expected a finite number, found {col[bad[0]]}")

    @property
    def record_length(self) -> float:
        """T_sum = N Ts [s]."""
        return len(self) * self.ts

    def column(self, name: str, *, role: str = "column") -> np.ndarray:
        """A column by name, refusing a missing one with the available names."""
        try:
            return self.columns[name]
        except KeyError:
            have = ", ".join(self.columns)
            raise DataFormatError(
                f"{self.source}: column {name!r}",
                f"expected a {role} named {name!r}, found only: {have}{self.note}",
            ) from None

    def window(self, start: int, stop: int | None = None) -> DataLog:
        """Samples ``start:stop`` as a log of their own (e.g. to hold part of a log out)."""
        cols = {k: np.ascontiguousarray(v[start:stop]) for k, v in self.columns.items()}
        if not len(next(iter(cols.values()))):
            raise DataFormatError(f"{self.source}: rows {start}:{stop}", "expected samples, found none")
        digest = hashlib.sha256(f"{self.sha256}[{start}:{stop}]".encode()).hexdigest()
        return DataLog(cols, self.ts, f"{self.source}[{start}:{stop}]", digest, dict(self.scalars),
                       dict(self.roles))

    def stack(self, names: Iterable[str]) -> np.ndarray:
        """The named columns as a (len(names), N) array."""
        return np.vstack([self.column(n, role="input column") for n in names])


def load_data(
    path: str | Path, *, ts: float | None = None, require: Iterable[str] = (),
    default_ts: float | None = None, columns: ColumnRoles | None = None,
    names: str | Sequence[str] | None = None,
) -> DataLog:
    """Read a log from CSV, .npz, .mat, HDF5 (.h5, .hdf5) or Parquet.

    Parameters
    ----------
    path : path-like or str
        The file; the suffix picks the reader (``.npz``, ``.mat``, ``.h5``,
        ``.hdf5``, ``.parquet``, else CSV). ``FILE:SEL[,SEL...]`` selects in a
        file of named arrays: a struct or group, a field (``run.omega``) or a
        matrix (docs/data.md#files-loggers-write).
        A ``plant:`` spec is not a file: :func:`edm_sym.engines.sources.load_data`
        simulates it (this layer never imports the plant).
    ts : float, optional
        Sample time [s] when the log has no ``t`` column; with a ``t`` column
        it must agree with it.
    require : iterable of str
        Column names that must be present.
    default_ts : float, optional
        Sample time [s] for a log with neither a time column nor ``ts``: the
        one a model file records, so a user need not give it again.
    columns : ColumnRoles, optional
        The roles of its columns (``--time-column``, ``--role``, a ``[columns]``
        table, or those a model recorded): the ``time`` column replaces ``t``,
        and every column named must be present (but for ``columns.loose`` ones,
        whose roles are dropped when absent).
    names : str or sequence of str, optional
        The names of the columns of a selected matrix (``"t,ref,theta"``:
        ``--columns``), in its column order.

    Returns
    -------
    DataLog

    Raises
    ------
    DataFormatError
        Naming the file and the row or column at fault.
    """
    if is_plant_spec(path):
        raise DataFormatError(str(path), "expected a file; a plant: spec is simulated by "
                              "edm_sym.engines.sources.load_data (or edm_sym.load_data)")
    path, selection = split_spec(path)
    names = parse_names(names)
    name = path.name if selection is None else f"{path.name}:{selection}"
    try:
        size = path.stat().st_size
    except OSError:
        size = 0  # read_bytes below says why
    # A file whose bytes alone cannot fit is refused before it is read.
    budget.check(budget.Estimate(size, 0.0, f"a {budget.format_bytes(size)} file"), name,
                 budget.LOG_HINT)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise DataFormatError(str(path), f"cannot be read ({exc.strerror})") from None
    if not raw.strip():
        raise DataFormatError(name, "expected a header row and data, found an empty file")
    suffix = path.suffix.lower()
    scalars: dict[str, float] = {}
    skipped: dict[str, str] = {}  # arrays of a .npz/.mat that are no column, and what they are
    note = ""
    if selection is not None and suffix not in SELECTABLE:
        raise DataFormatError(name, f"expected a selection FILE:NAME in a file of named arrays "
                              f"({', '.join(SELECTABLE)}), found a {suffix or 'suffix-less'} file")
    if suffix in SELECTABLE:
        tree = read_tree(path.name, raw, suffix)
        if selection is not None:
            arrays, scalars, skipped = _read_arrays(name, select(name, path.name, tree, selection,
                                                                 names))
        else:
            if names is not None:
                raise DataFormatError("names", f"expected a matrix selected to name the columns "
                                      f"of ({path.name}:NAME), found {path.name} whole")
            arrays, scalars, skipped = _read_arrays(name, tree, hint=selection_hint(path.name, tree))
            note = _hidden(name, tree, arrays)
    else:
        if names is not None:
            raise DataFormatError("names", f"expected a file of named arrays "
                                  f"({', '.join(SELECTABLE)}) to select a matrix in, found {name}")
        # The sizes first (line ends and the header's cells): a log that cannot fit is refused
        # before its values are parsed.
        first = raw.split(b"\n", 1)[0]
        lines = raw.count(b"\n") + (not raw.endswith(b"\n"))
        budget.check(budget.log_estimate(file_bytes=len(raw), n_samples=max(1, lines - 1),
                                         n_columns=first.count(b",") + 1), name, budget.LOG_HINT)
        arrays = _read_csv(name, raw)
    log = with_roles(DataLog(arrays, 1.0, name, hashlib.sha256(raw).hexdigest(), scalars,
                             note=note), columns)
    time = log.time_column
    if ts is None and time is None:
        ts = default_ts
    # Rows in messages: file lines for CSV (header is line 1), sample numbers otherwise.
    log_ts = _sample_time(name, arrays, time, ts, row_offset=1 if suffix in SELECTABLE else 2)
    log = replace(log, ts=log_ts)
    for col in require:
        if col in skipped and col not in log.columns:
            raise DataFormatError(f"{name}: column {col!r}",
                                  f"expected a 1-D array of real numbers, found {skipped[col]}")
        log.column(col)
    return log


def _hidden(name: str, tree: Mapping[str, object], columns: Mapping[str, np.ndarray]) -> str:
    """What a file read whole leaves aside that looks like the samples: a note for messages.

    Raises
    ------
    DataFormatError
        When a matrix holds more samples than the file's columns: its columns are the log,
        not the arrays beside it.
    """
    n = max((len(c) for c in columns.values()), default=0)
    hint = selection_hint(Path(name).name, dict(tree))
    if not hint:
        return ""
    if any(is_matrix(v) and max(np.shape(v)) > n for v in tree.values()):
        raise DataFormatError(name, f"expected the log's samples in 1-D arrays, found them in a "
                              f"matrix; the file holds {contents(dict(tree))}{hint}")
    return f"; {name} also holds {contents({k: v for k, v in tree.items() if k not in columns})}{hint}"


def with_roles(log: DataLog, columns: ColumnRoles | None) -> DataLog:
    """``log`` with the column roles given (see :func:`load_data`'s ``columns``).

    Raises
    ------
    DataFormatError
        A column named by a role that the log does not have (roles that are
        not ``loose``).
    """
    if columns is None or not columns.roles:
        return log
    roles = {}
    for col, role in columns.roles.items():
        if col in log.columns:
            roles[col] = role
        elif col not in columns.loose:
            have = ", ".join(log.columns)
            raise DataFormatError(f"{log.source}: column {col!r}",
                                  f"expected a {role} column named {col!r}, found only: "
                                  f"{have}{log.note}")
    return replace(log, roles=roles)


def _cut(text: str, width: int = 30) -> str:
    """``text`` cut for a message (a number of thousands of digits stays one short line)."""
    return text if len(text) <= width else f"{text[:width - 12]}... ({len(text)} characters)"


def _read_csv(name: str, raw: bytes) -> dict[str, np.ndarray]:
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise DataFormatError(name, "expected UTF-8 text, found binary data") from None
    reader = csv.reader(_lines(text))
    try:
        return _parse_csv(name, reader, rows=text.count("\n") + 1)
    except csv.Error as exc:  # an unterminated quote, a cell beyond the csv module's size limit
        raise DataFormatError(f"{name}: row {reader.line_num}",
                              f"expected CSV cells of numbers, found unreadable text ({exc})") from None


def _lines(text: str) -> Iterator[str]:
    """The lines of ``text``, each with its line end, one at a time (no copy of the whole)."""
    start, end = 0, len(text)
    while start < end:
        stop = text.find("\n", start)
        stop = end if stop < 0 else stop + 1
        yield text[start:stop]
        start = stop


def _parse_csv(name: str, reader, rows: int) -> dict[str, np.ndarray]:  # noqa: ANN001
    header = next(reader, None)
    if not header or not any(h.strip() for h in header):
        raise DataFormatError(f"{name}: row 1", "expected a header row of column names, found none")
    header = [h.strip() for h in header]
    for k, h in enumerate(header):
        if not h:
            raise DataFormatError(f"{name}: row 1, column {k + 1}", "expected a column name, found nothing")
        if header.index(h) != k:
            raise DataFormatError(f"{name}: row 1, column {h!r}", "expected unique names, found it twice")
    # One array, a column per row of it, filled as the file is read: no Python float per
    # value is kept (a list of them takes about four times the array's memory).
    values = np.empty((len(header), max(1, rows)), dtype=float)
    count = 0
    for lineno, cells in enumerate(reader, start=2):
        if not cells or all(not c.strip() for c in cells):
            continue
        if len(cells) != len(header):
            raise DataFormatError(f"{name}: row {lineno}",
                                  f"expected {len(header)} values, found {len(cells)}")
        row = []
        for col, cell in zip(header, cells, strict=True):
            try:
                if "_" in cell:  # Python's float() reads 1_06.28 as 106.28: no CSV number
                    raise ValueError(cell)
                v = float(cell)
            except ValueError:
                raise DataFormatError(f"{name}: row {lineno}, column {col!r}",
                                      f"expected a number, found {cell.strip()[:30]!r}") from None
            if not math.isfinite(v):
                raise DataFormatError(f"{name}: row {lineno}, column {col!r}",
                                      f"expected a finite number, found {_cut(cell.strip())}")
            row.append(v)
        if count == values.shape[1]:  # more records than line ends (a lone \r ends one)
            values = np.concatenate([values, np.empty_like(values)], axis=1)
        values[:, count] = row
        count += 1
    if not count:
        raise DataFormatError(name, "expected data rows below the header, found none")
    if count < values.shape[1]:
        values = values[:, :count].copy() if count < values.shape[1] // 2 else values[:, :count]
    return {h: values[k] for k, h in enumerate(header)}


def _read_arrays(
    name: str, arrays: Mapping[str, object], *, hint: str = ""
) -> tuple[dict[str, np.ndarray], dict[str, float], dict[str, str]]:
    columns: dict[str, np.ndarray] = {}
    scalars: dict[str, float] = {}
    skipped: dict[str, str] = {}
    for key, arr in arrays.items():
        if isinstance(arr, Mapping):
            skipped[key] = describe(arr)
            continue
        arr = np.asarray(arr)
        if arr.dtype.kind == "m":  # a timedelta64 (numpy counts it an integer): in seconds
            arr = arr / np.timedelta64(1, "s")
        if np.iscomplexobj(arr):
            skipped[key] = f"a complex array of shape {arr.shape}"
        elif not np.issubdtype(arr.dtype, np.number):
            kind = "text" if arr.dtype.kind in "US" else str(arr.dtype)
            skipped[key] = f"an array of {kind} of shape {arr.shape}"
        elif arr.size == 1:
            scalars[key] = float(arr.reshape(()))
        elif arr.ndim == 1 or (arr.ndim == 2 and 1 in arr.shape):
            columns[key] = np.ascontiguousarray(arr.reshape(-1), dtype=float)
        else:
            skipped[key] = f"a {arr.ndim}-D array of shape {arr.shape}"
    if not columns:
        found = ", ".join(f"{k} ({describe(v)})" for k, v in arrays.items()) or "none"
        raise DataFormatError(name, f"expected one or more 1-D numeric arrays, found {found}{hint}")
    n = max(len(c) for c in columns.values())
    for key, col in columns.items():
        if len(col) != n:
            raise DataFormatError(f"{name}: column {key!r}",
                                  f"expected {n} samples like the longest column, found {len(col)}")
        bad = np.flatnonzero(~np.isfinite(col))
        if bad.size:
            raise DataFormatError(f"{name}: row {bad[0] + 1}, column {key!r}",
                                  f"expected a finite number, found {col[bad[0]]}")
    return columns, scalars, skipped


def drift(ts: float, model_ts: float) -> float:
    """The relative difference of a log's sample time from a model's, or 0 below
    :data:`TIME_ROUNDING` (the rounding of a time column's steps: no drift to note)."""
    rel = abs(ts - model_ts) / model_ts
    return rel if rel > TIME_ROUNDING else 0.0


def check_sample_time(where: str, ts: float, what: str = "a sample time") -> float:
    """Refuse a sample time outside :data:`TS_RANGE` (a positive finite number assumed).

    Raises
    ------
    DataFormatError
        Naming ``where``, the range and the value.
    """
    low, high = TS_RANGE
    if not low <= ts <= high:
        raise DataFormatError(where, f"expected {what} from {low:g} s to {high:g} s, "
                                     f"found {ts:g} s")
    return ts


def _sample_time(
    name: str, columns: Mapping[str, np.ndarray], time: str | None, ts: float | None, *,
    row_offset: int,
) -> float:
    if ts is not None and not (math.isfinite(ts) and ts > 0):
        raise DataFormatError(f"{name}: ts", f"expected a positive sample time, found {ts}")
    if ts is not None:
        check_sample_time(f"{name}: ts", ts)
    if time is None:
        if ts is None:
            raise DataFormatError(f"{name}: column {DEFAULT_TIME!r}",
                                  f"expected a time column {DEFAULT_TIME!r} (or one named by "
                                  "`time_column`) or the option `ts=SECONDS`, found neither")
        return float(ts)
    t = columns[time]
    if len(t) < 2:
        raise DataFormatError(f"{name}: column {time!r}", f"expected at least 2 samples, found {len(t)}")
    dt = np.diff(t)
    back = np.flatnonzero(dt <= 0)
    if back.size:
        k = int(back[0])
        what = "a repeated" if dt[k] == 0 else "a decreasing"
        raise DataFormatError(f"{name}: row {k + 1 + row_offset}, column {time!r}",
                              f"expected increasing time stamps, found {what} one "
                              f"({t[k + 1]:.9g} s after {t[k]:.9g} s)")
    step = float(np.median(dt))
    bad = np.flatnonzero(np.abs(dt - step) > JITTER_RTOL * step)
    if bad.size:
        k = int(bad[0])
        kind = f"a gap of {dt[k] / step - 1:.3g} samples" if dt[k] > step else "a short step"
        raise DataFormatError(
            f"{name}: row {k + 1 + row_offset}, column {time!r}",
            f"expected uniform sampling (step {step:g} s, jitter up to {JITTER_RTOL:.0%}), "
            f"found a step of {dt[k]:g} s ({kind})",
        )
    # The sample time is the mean step: exact on a uniform grid and, unlike the
    # median, unbiased by per-stamp jitter (its error shrinks as 1/N).
    step = float(t[-1] - t[0]) / (len(t) - 1)
    check_sample_time(f"{name}: column {time!r}", step, "the step of the time stamps")
    if ts is not None and abs(ts - step) > TIME_RTOL * step:
        raise DataFormatError(f"{name}: ts",
                              f"expected the step of column {time!r} ({step:g} s), found {ts:g}")
    return step


def match_sample_time(data: DataLog, ts: float, *, model: str, resample: bool = False) -> DataLog:
    """Check a log against a model's sample time; resample it onto the model's grid if asked.

    A second recording of the same drive never has exactly the model's sample
    time: the logger's clock drifts. A relative difference up to
    :data:`TIME_RTOL` is accepted and the log is used as it is (its own sample
    time stays in ``data.ts``; callers report both). A larger one is refused,
    unless ``resample`` is true: then every column is resampled onto the
    model's grid with a polyphase anti-aliasing filter
    (:func:`scipy.signal.resample_poly`, the ratio as a fraction of integers
    below 1000) and the time column is rebuilt.

    Parameters
    ----------
    data : DataLog
    ts : float
        The model's sample time [s].
    model : str
        The model file's name, for messages.
    resample : bool
        Resample a log whose sample time differs by more than the tolerance.

    Returns
    -------
    DataLog
        ``data`` itself, or its resampled copy (``ts`` = the model's).

    Raises
    ------
    DataFormatError
        When the sample times differ by more than :data:`TIME_RTOL` and
        ``resample`` is false, or no integer ratio below 1000 reaches the
        model's sample time within the tolerance.
    """
    if abs(data.ts - ts) <= TIME_RTOL * ts:
        return data
    where = f"{data.source}: sample time"
    if not resample:
        raise DataFormatError(where, f"expected {ts:g} s as in {model} (within {TIME_RTOL:g} relative), "
                              f"found {data.ts:g} s; `resample=True` resamples the log onto the model's grid")
    from fractions import Fraction

    from scipy import signal

    ratio = Fraction(data.ts / ts).limit_denominator(1000)  # up / down
    up, down = ratio.numerator, ratio.denominator
    # Both below 1000 (docs/data.md): a larger up-sampling factor would make a log of
    # up times the samples (1e6 for 1000 s onto 1 ms: the process was killed for memory).
    if not (1 <= up < 1000 and down < 1000) or abs(data.ts * down / up - ts) > TIME_RTOL * ts:
        raise DataFormatError(where, f"expected a ratio of small integers to the model's {ts:g} s, "
                              f"found {data.ts:g} s (best {up}/{down})")
    time = data.time_column
    cols = {}
    for key, col in data.columns.items():
        if key == time:
            continue
        cols[key] = np.ascontiguousarray(signal.resample_poly(col, up, down, padtype="line"))
    n = len(next(iter(cols.values()))) if cols else 0
    if n < 2:
        raise DataFormatError(where, f"expected at least 2 samples after resampling, found {n}")
    # The time column keeps its place and its first value; its steps become the model's.
    out = {key: (float(data.columns[time][0]) + ts * np.arange(n) if key == time else cols[key])
           for key in data.columns}
    digest = hashlib.sha256(f"{data.sha256}@resample:{up}/{down}".encode()).hexdigest()
    return DataLog(out, ts, f"{data.source} (resampled {up}/{down})", digest, dict(data.scalars),
                   dict(data.roles))


def join_logs(logs: Sequence[DataLog], names: Sequence[str]) -> DataLog:
    """Several logs of one axis laid end to end, for a fit over all of them.

    Only the columns ``names`` (the target and the inputs) and the time
    column are kept. The joined log is a container: whoever simulates it
    must start every log from rest (``starts`` of
    :func:`edm_sym.engines.simulate.simulate_row`); its ``times`` are each
    log's own time stamps.

    Raises
    ------
    DataFormatError
        Naming the file: a column missing, a sample time unlike the first
        log's (beyond :data:`TIME_RTOL`), a column given another role, or a
        time column where the first log has none (or the other way round).
    """
    first = logs[0]
    time = first.time_column
    for log in logs:
        for name in names:
            log.column(name, role="target column" if name == names[0] else "input column")
        if abs(log.ts - first.ts) > TIME_RTOL * first.ts:
            raise DataFormatError(f"{log.source}: sample time",
                                  f"expected {first.ts:g} s as in {first.source} (the logs of one "
                                  f"abstraction share it; `decimate` or resample), found {log.ts:g} s")
        if (log.time_column is None) != (time is None):
            raise DataFormatError(f"{log.source}: column {time or log.time_column!r}",
                                  f"expected {'a' if time else 'no'} time column as in "
                                  f"{first.source}, found {'none' if time else 'one'}")
        for name in names:
            if log.role_of(name) != first.role_of(name):
                raise DataFormatError(f"{log.source}: column {name!r}",
                                      f"expected the role {first.role_of(name)!r} as in "
                                      f"{first.source}, found {log.role_of(name)!r}")
    keep = ([time] if time is not None else []) + [n for n in names if n != time]
    cols = {}
    for name in keep:
        cols[name] = np.concatenate([
            np.asarray(log.columns[log.time_column if name == time else name], dtype=float)
            for log in logs])
    digest = hashlib.sha256(" ".join(str(log.sha256) for log in logs).encode()).hexdigest()
    roles = {c: r for c, r in first.roles.items() if c in cols}
    return DataLog(cols, float(first.ts), " + ".join(log.source for log in logs), digest,
                   dict(first.scalars), roles)


#: The anti-alias filter of :func:`decimate`, as recorded in the provenance.
DECIMATE_FILTER = ("FIR, Hamming window, 20 K + 1 taps, corner at the new Nyquist frequency, "
                   "zero phase, ends extended as lines (scipy.signal.resample_poly)")


def decimate(log: DataLog, factor: int, *, where: str = "factor") -> DataLog:
    """Every ``factor``-th sample of ``log``, each column low-pass filtered first.

    The anti-alias filter is the FIR of :func:`scipy.signal.decimate`
    (Hamming window, ``20 factor + 1`` taps, corner at the new Nyquist
    frequency), centred (no phase lag) and with a DC gain of exactly 1 (the
    IIR default of ``decimate`` scales a constant by 0.989), applied by
    :func:`scipy.signal.resample_poly` with the ends extended as lines. The
    time column is taken as it is at the kept samples; a wrapped angle (role
    ``position_wrapped``) is unwrapped, filtered and wrapped again, so its
    jumps are not smeared.

    ``where`` names the factor in messages (a command passes its option, ``"--decimate"``).

    Raises
    ------
    DataFormatError
        A factor below 1, or a log too short to filter (naming the file).
    """
    if isinstance(factor, bool) or not isinstance(factor, numbers.Integral) or factor < 1:
        raise DataFormatError(where, f"expected an integer >= 1, found {factor!r}")
    if factor == 1:
        return log
    from scipy import signal

    need = 2 * factor  # two samples kept
    if len(log) < need:
        raise DataFormatError(f"{log.source}: {where}", f"expected at least {need} samples to "
                              f"keep two after decimating by {factor}, found {len(log)}")
    taps = signal.firwin(20 * factor + 1, 1.0 / factor, window="hamming")

    def filtered(x: np.ndarray) -> np.ndarray:
        return signal.resample_poly(x, 1, factor, window=taps, padtype="line")

    time = log.time_column
    cols = {}
    for name, col in log.columns.items():
        x = np.asarray(col, dtype=float)
        if name == time:
            cols[name] = np.ascontiguousarray(x[::factor])
        elif log.role_of(name) == "position_wrapped":
            low = -math.pi if np.min(x) < 0 else 0.0
            y = filtered(np.unwrap(x))
            w = np.mod(y - low, 2 * math.pi)
            w[w >= 2 * math.pi] = 0.0  # mod of a tiny negative number rounds up to 2 pi
            cols[name] = np.ascontiguousarray(w + low)
        else:
            cols[name] = np.ascontiguousarray(filtered(x))
    digest = hashlib.sha256(f"{log.sha256}@decimate:{factor}".encode()).hexdigest()
    ts = float(log.ts) * factor
    if time is not None:
        t = cols[time]
        ts = float(t[-1] - t[0]) / (len(t) - 1) if len(t) > 1 else ts
    return DataLog(cols, ts, f"{log.source} (decimated {factor})", digest, dict(log.scalars),
                   dict(log.roles), decimation=log.decimation * factor)


def decimation_factor(log: DataLog, target: float, *, where: str = "target") -> int:
    """The factor K that takes ``log`` to the sample time ``target`` (``K = target / ts``).

    ``where`` names the target in messages (a command passes its option, ``"--decimate-to"``).

    Raises
    ------
    DataFormatError
        Naming the file: a target that is not a whole multiple (within
        :data:`TIME_RTOL`) of the log's sample time, or is below it.
    """
    if not (isinstance(target, numbers.Real) and math.isfinite(target) and target > 0):
        raise DataFormatError(where, f"expected a sample time in seconds > 0, found {target!r}")
    ratio = float(target) / float(log.ts)
    factor = round(ratio)
    if factor < 1 or abs(factor - ratio) > TIME_RTOL * ratio:
        raise DataFormatError(f"{log.source}: {where}",
                              f"expected a whole multiple of the log's sample time {log.ts:g} s, "
                              f"found {target:g} s ({ratio:.6g} times it)")
    return int(factor)


def write_csv(path: str | Path, columns: Mapping[str, np.ndarray]) -> Path:
    """Write columns as CSV atomically, with round-trip float precision.

    Parameters
    ----------
    path : path-like
        Destination.
    columns : mapping of str to array
        Equally long columns, written in mapping order.
    """
    names = list(columns)
    arr = np.column_stack([np.asarray(columns[n], dtype=float) for n in names])
    buf = io.StringIO()
    buf.write(",".join(names) + "\n")
    np.savetxt(buf, arr, delimiter=",", fmt="%.17g")
    return write_atomic(path, buf.getvalue())
