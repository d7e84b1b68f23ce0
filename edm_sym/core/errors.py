"""Errors and warnings raised by edm_sym.

Every error that reaches a user names where the problem is, what was expected
and what was found, so the command line can print it as one line and exit 2.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from types import MappingProxyType

#: The problem of a JSON or TOML document too deeply nested for Python's parsers.
TOO_DEEP = "expected a document nested at most about a thousand levels deep, found deeper nesting"
#: The target among the inputs: a model would reproduce it from itself (fitness 0).
TARGET_AS_INPUT = ("expected input columns other than the target, found the target {target!r} "
                   "(a model of it from itself fits trivially)")


class EdmError(Exception):
    """Base class of the errors edm_sym raises on bad input."""


class ResultFormatError(EdmError, ValueError):
    """A result (or model) file is not a valid edm_sym file.

    Parameters
    ----------
    where : str
        The file, and the field inside it, e.g. ``"result.json: rows[3].elements[2].code"``.
    problem : str
        What is wrong: expected and found, and a hint when there is one.
    """

    def __init__(self, where: str, problem: str):
        self.where = where
        self.problem = problem
        super().__init__(f"{where}: {problem}")


class DataFormatError(EdmError, ValueError):
    """A data log cannot be used: missing column, NaN, non-uniform time, ...

    Parameters
    ----------
    where : str
        The file, and the row or column inside it.
    problem : str
        What is wrong: expected and found.
    """

    def __init__(self, where: str, problem: str):
        self.where = where
        self.problem = problem
        super().__init__(f"{where}: {problem}")


class ConfigError(EdmError, ValueError):
    """A configuration (TOML) file or an option value is invalid."""

    def __init__(self, where: str, problem: str):
        self.where = where
        self.problem = problem
        super().__init__(f"{where}: {problem}")


class BudgetError(EdmError, ValueError):
    """Work that cannot fit: more memory or time than a machine has (edm_sym.core.budget).

    Parameters
    ----------
    where : str
        The file and key, or the option, whose sizes ask for the work.
    problem : str
        The estimate, the limit it exceeds, and what to make smaller.
    """

    def __init__(self, where: str, problem: str):
        self.where = where
        self.problem = problem
        super().__init__(f"{where}: {problem}")


class OutputError(EdmError, OSError):
    """The output folder or a file in it cannot be created or written."""


class ToolMissingError(EdmError, RuntimeError):
    """An optional external tool (latexmk, arm-none-eabi-gcc, ...) is not installed."""


class ExternalToolError(RuntimeError):
    """An external tool (LaTeX, a compiler) failed on valid input: exit 1, not a bug of edm_sym."""


class NumericsWarning(UserWarning):
    """Doubtful numerics: an unstable filter, a parameter at its range limit, ..."""


class ClockWarning(UserWarning):
    """An input that only rises (or only falls) over a log: within that run it is a clock."""


class BudgetWarning(UserWarning):
    """A size that fits but is worth a word: a compensator state larger than a microcontroller's RAM."""


#: The command-line option (docs/cli.md) that gives each parameter of the Python API an
#: error may name. The library names the parameter (``prefix: expected a C identifier``,
#: ``use real="float"``), as a Python caller passed it; a command prints the option
#: (:func:`as_options`). ``decimate`` is the function :func:`edm_sym.core.data.decimate`,
#: which a command's ``--decimate`` calls.
OPTIONS: Mapping[str, str] = MappingProxyType({
    "prefix": "--prefix",
    "real": "--real",
    "axis": "--axis",
    "pdf": "--pdf",
    "input_range": "--input-range",
    "scheduler": "--scheduler",
    "validation_share": "--validation-share",
    "searches": "--searches",
    "observer_bandwidth": "--observer-bandwidth",
    "ts": "--ts",
    "names": "--columns",
    "time_column": "--time-column",
    "roles": "--role",
    "resample": "--resample",
    "decimate": "--decimate",
})

#: The parameters an error names after the file they were given for (``log.csv: ts``):
#: how a log is read. There a command prints their options too (:func:`where_as_options`);
#: another name after a file is one of its keys or scalars (``cfg.toml: axis``,
#: ``log.csv: observer_bandwidth``) and stays as it is.
LOG_PARAMETERS = frozenset({"ts", "names", "time_column", "roles", "resample"})

# The ways a message names a parameter: its first field (``prefix: ...``), a value in a
# hint (``real="float"``), one input's range (``input_range={"omega": (LO, HI)}``); the
# bare name in parentheses (``(input_range)``); and the name in backquotes, alone, with a
# placeholder or set true: `time_column`, `ts=SECONDS`, `resample=True`.
_FIRST = re.compile(r"^(\w+):")
_VALUE = re.compile(r"\b(\w+)=\"([^\"]*)\"")
_RANGE = re.compile(r"\binput_range=\{\"([^\"]+)\": \(LO, HI\)\}")
_BARE = re.compile(r"(?<![\w.])\((\w+)\)")
_QUOTED = re.compile(r"`(\w+)(?:=([^`]*))?`")


def as_options(message: str) -> str:
    """A library message as a command prints it: each parameter it names (:data:`OPTIONS`)
    as the option that gives it.

    ``prefix: expected a C identifier`` becomes ``--prefix: expected a C identifier``,
    ``use real="float"`` becomes ``use --real float``, ``input_range={"omega": (LO, HI)}``
    becomes ``--input-range omega=LO:HI``; a name in backquotes becomes its option
    (`time_column` ``--time-column``), with its placeholder (`ts=SECONDS` ``--ts SECONDS``)
    or alone when set true (`resample=True` ``--resample``); other text is left as it is.
    """
    def first(m: re.Match[str]) -> str:
        return f"{OPTIONS[m[1]]}:" if m[1] in OPTIONS else m[0]

    def value(m: re.Match[str]) -> str:
        return f"{OPTIONS[m[1]]} {m[2]}" if m[1] in OPTIONS else m[0]

    def bare(m: re.Match[str]) -> str:
        return f"({OPTIONS[m[1]]})" if m[1] in OPTIONS else m[0]

    def quoted(m: re.Match[str]) -> str:
        if m[1] not in OPTIONS:
            return m[0]
        return OPTIONS[m[1]] if m[2] in (None, "True") else f"{OPTIONS[m[1]]} {m[2]}"

    message = _FIRST.sub(first, message, count=1)
    message = _RANGE.sub(lambda m: f"{OPTIONS['input_range']} {m[1]}=LO:HI", message)
    return _QUOTED.sub(quoted, _BARE.sub(bare, _VALUE.sub(value, message)))


def where_as_options(where: str) -> str:
    """The place of an error about a log as a command prints it: the parameter named after
    the file (:data:`LOG_PARAMETERS`, the last ``": "``-separated part) as its option.

    ``log.csv: ts`` becomes ``log.csv: --ts``; ``log.csv: column 't'`` and
    ``log.csv: observer_bandwidth`` (a scalar of the log) are left as they are. A name
    alone (``ts``) is the message's first field, which :func:`as_options` maps.
    """
    head, sep, last = where.rpartition(": ")
    return f"{head}{sep}{OPTIONS[last]}" if sep and last in LOG_PARAMETERS else where
