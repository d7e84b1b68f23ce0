"""Output files: checked before the work starts, written atomically, never over an input.

A regular file is either fully written or not there at all (a temporary file
and a rename). A device, a FIFO or a terminal (``-o /dev/null``, ``-o
/dev/stdout``) is written directly: renaming over it would replace it with a
regular file. A symbolic link is followed, so its target is written and the
link stays. :func:`check_outputs` refuses, before any long work, an output that
is an input (also through a link) or that cannot be written.
"""

from __future__ import annotations

import json
import os
import re
import stat
import sys
import tempfile
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

from edm_sym.core.errors import TOO_DEEP, EdmError, OutputError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

_toml_loads = tomllib.loads
_TomlError = tomllib.TOMLDecodeError


def _current_umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


_UMASK = _current_umask()


def _is_special(path: Path) -> bool:
    """True for an existing non-regular, non-folder file: a device, FIFO, socket or terminal."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return False
    return not (stat.S_ISREG(mode) or stat.S_ISDIR(mode))


def write_atomic(path: str | os.PathLike, data: str | bytes) -> Path:
    """Write ``data`` to ``path`` through a temporary file and a rename.

    Parameters
    ----------
    path : path-like
        Destination file. Its folder is created when missing. A symbolic link
        is followed; a device or FIFO is written directly.
    data : str or bytes
        Text (written as UTF-8 with ``\\n`` newlines) or raw bytes.

    Returns
    -------
    pathlib.Path
        The written path.

    Raises
    ------
    OutputError
        When the file or its folder cannot be created or written (the path
        and the system's reason named).
    """
    path = Path(path)
    raw = data.encode("utf-8") if isinstance(data, str) else data
    if path.is_symlink():
        path = Path(os.path.realpath(path))
    if _is_special(path):
        try:
            with open(path, "wb") as fh:
                fh.write(raw)
        except OSError as exc:
            raise OutputError(f"{path}: cannot write ({exc.strerror})") from None
        return path
    if path.is_dir():
        raise OutputError(f"{path}: expected a file to write, found a folder")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    except OSError as exc:
        raise OutputError(f"{path}: cannot create the file ({exc.strerror})") from None
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(raw)
        # mkstemp makes the file private (0600); give it the usual mode for new files.
        os.chmod(tmp, 0o666 & ~_UMASK)
        os.replace(tmp, path)
    except BaseException as exc:
        if os.path.exists(tmp):
            os.unlink(tmp)
        if isinstance(exc, OSError):
            raise OutputError(f"{path}: cannot write ({exc.strerror})") from None
        raise
    return path


def _same_file(a: Path, b: Path) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:  # one of them does not exist yet
        return os.path.realpath(a) == os.path.realpath(b)


def _writable(path: Path) -> str | None:
    """Why ``path`` cannot be written, or None when it can (nothing is left behind)."""
    if path.is_dir():
        return "expected a file to write, found a folder"
    if path.exists():
        if _is_special(path):
            return None if os.access(path, os.W_OK) else "cannot write it (permission denied)"
        if not os.access(path, os.W_OK):
            return "cannot write it (permission denied)"
    folder = path.parent
    while not folder.exists():  # the first folder that exists must let us create the rest
        if folder.parent == folder:
            break
        folder = folder.parent
    if not folder.is_dir():
        return f"cannot create the output folder ({folder} is a file)"
    if not os.access(folder, os.W_OK | os.X_OK):
        return f"cannot write in {folder} (permission denied)"
    # The permission bits do not tell all (root in /proc, a read-only mount): make and
    # remove what the write will make there first, a file or the output's folder.
    try:
        if folder == path.parent:
            fd, probe = tempfile.mkstemp(dir=folder, prefix=f".{path.name}.", suffix=".probe")
            os.close(fd)
            os.unlink(probe)
        else:
            os.rmdir(tempfile.mkdtemp(dir=folder, prefix=".edm-", suffix=".probe"))
    except OSError as exc:
        return f"cannot write in {folder} ({exc.strerror or exc})"
    return None


def check_outputs(outputs: Iterable[str | os.PathLike], inputs: Iterable[object] = (), *,
                  option: str = "-o") -> None:
    """Refuse, before any work, outputs that would harm an input or cannot be written.

    Parameters
    ----------
    outputs : iterable of path-like
        Every file the command will write (a folder output: the files in it).
    inputs : iterable of path-like or str
        Every file the command reads; strings that are not paths (``plant:``
        specs) are skipped.
    option : str
        The option that named the outputs, for messages.

    Raises
    ------
    OutputError
        Naming the output and the input it is, or why it cannot be written.
    """
    ins = [Path(i) for i in inputs if isinstance(i, str | os.PathLike)
           and not str(i).startswith("plant:") and Path(i).exists()]
    for out in (Path(o) for o in outputs):
        for src in ins:
            if _same_file(out, src):
                raise OutputError(f"{option} {out}: expected a new file, found the input {src} "
                                  "(writing would destroy it); choose another output name")
        why = _writable(out)
        if why:
            raise OutputError(f"{option} {out}: {why}")


def _finite_only(token: str) -> float:
    raise ValueError(f"{token} is not allowed (numbers must be finite)")


#: Python refuses to read an integer of more digits than this from text
#: (``sys.get_int_max_str_digits``); every such integer overflows a double anyway.
INT_DIGITS_LIMIT = 4300
#: Every integer of more digits than this overflows a double (its largest is about 1.8e308).
_DOUBLE_DIGITS = 309


class _LongInteger:
    """An integer read from a file that no double can hold (it is not converted: too long)."""

    __slots__ = ("digits",)

    def __init__(self, digits: int) -> None:
        self.digits = digits


def _overflows(value: Any) -> bool:
    if isinstance(value, _LongInteger):
        return True
    if not isinstance(value, int) or isinstance(value, bool):
        return False
    try:
        float(value)
    except OverflowError:
        return True
    return False


def _long_problem(value: Any) -> str:
    if isinstance(value, _LongInteger):
        digits = value.digits
    else:
        digits = len(str(abs(value))) if abs(value) != _TOML_STAND_IN else None
    count = f"{digits} digits" if digits is not None else f"more than {INT_DIGITS_LIMIT} digits"
    return (f"expected a finite number, found an integer of {count} "
            "(it overflows a double)")


def _first_overflow(doc: Any) -> tuple[list[Any], Any] | None:
    """The path and value of the first integer (in document order) that overflows a double."""
    stack: list[tuple[list[Any], Any]] = [([], doc)]
    while stack:
        path, node = stack.pop()
        if _overflows(node):
            return path, node
        if isinstance(node, dict):
            stack.extend((path + [k], v) for k, v in reversed(list(node.items())))
        elif isinstance(node, list):
            stack.extend((path + [i], v) for i, v in reversed(list(enumerate(node))))
    return None


def refuse_long_integers(doc: Any, where: str, error: Callable[[str, str], EdmError]) -> None:
    """Refuse an integer no double can hold anywhere in ``doc``, naming its key.

    Parameters
    ----------
    doc : object
        A parsed JSON or TOML document.
    where : str
        The file, for messages.
    error : callable
        ``error(where, problem)`` makes the error raised.

    Raises
    ------
    EdmError
        ``error("<file>: <key path>", problem)`` for the first such integer.
    """
    found = _first_overflow(doc)
    if found is None:
        return
    from edm_sym.core.validation import json_path

    path, value = found
    key = json_path(path)
    raise error(f"{where}: {key}" if key else where, _long_problem(value))


def _json_int(token: str, seen: list[bool]) -> int | _LongInteger:
    digits = len(token.lstrip("-"))
    if digits > _DOUBLE_DIGITS:  # never converted: the conversion is slow, or refused
        seen.append(True)
        return _LongInteger(digits)
    value = int(token)
    if _overflows(value):
        seen.append(True)
    return value


def parse_json(text: str, where: str, error: Callable[[str, str], EdmError], *,
               finite: bool = True) -> Any:
    """Parse JSON text strictly: no duplicate keys, no integer a double cannot hold.

    Parameters
    ----------
    text : str
        The document.
    where : str
        The file, for messages.
    error : callable
        ``error(where, problem)`` makes the error raised.
    finite : bool
        Refuse ``NaN`` and ``Infinity`` too (a file the project writes with
        ``allow_nan=False``).

    Returns
    -------
    object
        The document.

    Raises
    ------
    EdmError
        Naming the file (with the line and column of a syntax error, or the key
        of an integer too long).
    """
    seen: list[bool] = []
    hooks: dict[str, Any] = {"parse_constant": _finite_only} if finite else {}
    try:
        doc = json.loads(text, parse_int=lambda token: _json_int(token, seen),
                         object_pairs_hook=_no_duplicates, **hooks)
    except json.JSONDecodeError as exc:
        raise error(f"{where}: line {exc.lineno} column {exc.colno}",
                    f"expected JSON, found invalid JSON ({exc.msg})") from None
    except ValueError as exc:
        raise error(where, f"expected JSON, found invalid JSON ({exc})") from None
    except RecursionError:
        raise error(where, TOO_DEEP) from None
    if seen:
        refuse_long_integers(doc, where, error)
    return doc


#: An integer literal of more digits than Python reads (in a value, not in a name).
_LONG_LITERAL = re.compile(r"(?<![\w.+-])([+-]?)[0-9][0-9_]{" + str(INT_DIGITS_LIMIT) + r",}(?![\w.])")
#: What such a literal is read as, to find its key: still too large for a double, and a
#: number no one writes.
_TOML_STAND_IN = int("31415926535897932384" * 16)


def read_utf8(path: str | os.PathLike, error: Callable[[str, str], EdmError], *,
              where: str, expected: str) -> str:
    """A file's text: ``error(path, "cannot be read (...)")`` when it cannot be read,
    ``error(where, "expected EXPECTED, found binary data")`` when it is not UTF-8."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise error(str(path), f"cannot be read ({exc.strerror})") from None
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        raise error(where, f"expected {expected}, found binary data") from None


def read_toml(path: str | os.PathLike, error: Callable[[str, str], EdmError], *,
              where: str | None = None) -> dict[str, Any]:
    """Read a TOML file (a config, a pipeline file) strictly.

    Every defect becomes ``error(where, problem)``: an unreadable file, text
    that is not UTF-8 or not TOML, nesting too deep, and an integer no double
    can hold (also one too long for Python to read), named by its key.

    Parameters
    ----------
    path : path-like
        The file.
    error : callable
        ``error(where, problem)`` makes the error raised.
    where : str, optional
        The file as messages name it (default: its name).

    Returns
    -------
    dict
        The document.
    """
    path = Path(path)
    where = path.name if where is None else where
    text = read_utf8(path, error, where=where, expected="UTF-8 TOML text")
    try:
        doc = _toml_loads(text)
    except _TomlError as exc:
        raise error(where, f"expected TOML, found invalid text ({exc})") from None
    except RecursionError:
        raise error(where, TOO_DEEP) from None
    except ValueError as exc:
        # An integer longer than Python reads (tomllib names no key): read it as a
        # stand-in as large, to name the key it is under.
        try:
            doc = _toml_loads(_LONG_LITERAL.sub(lambda m: m.group(1) + str(_TOML_STAND_IN), text))
        except (ValueError, RecursionError):
            raise error(where, f"expected TOML, found invalid text ({exc})") from None
        if _first_overflow(doc) is None:
            raise error(where, f"expected TOML, found invalid text ({exc})") from None
    refuse_long_integers(doc, where, error)
    return doc


def json_kind(value: Any) -> str:
    """The JSON name of a parsed value's type (for messages: ``null``, not ``NoneType``)."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, int | float):
        return "a number"
    if isinstance(value, str):
        return "a string"
    return "an array" if isinstance(value, list) else "an object"


def _no_duplicates(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    seen: dict[str, Any] = {}
    for key, value in pairs:
        if key in seen:
            raise ValueError(f"duplicate key {key!r}")
        seen[key] = value
    return seen


def read_json(path: str | os.PathLike, error: Callable[[str, str], EdmError]) -> tuple[Any, bytes]:
    """Read a JSON document strictly: finite numbers, no duplicate keys, bounded nesting.

    The one reader of the project's JSON files (result.json, LUGRE.json, any
    model file); every defect becomes ``error(where, problem)`` naming the file
    (and the line and column of a syntax error).

    Returns
    -------
    (document, raw bytes)
    """
    if not isinstance(path, str | os.PathLike):
        raise error("path", f"expected a file path, found {type(path).__name__}")
    path = Path(path)
    name = path.name
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise error(str(path), "no such file") from None
    except OSError as exc:
        raise error(str(path), f"cannot be read ({exc.strerror or exc})") from None
    try:
        text = raw.decode("utf-8-sig")  # a byte order mark (Windows editors) is no error
    except UnicodeDecodeError as exc:
        raise error(name, f"not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    doc = parse_json(text, name, error)
    return doc, raw
