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
import stat
import tempfile
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

from edm_sym.core.errors import TOO_DEEP, EdmError, OutputError


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


def _int_of_a_double(token: str) -> int:
    value = int(token)
    try:
        float(value)
    except OverflowError:
        shown = token if len(token) <= 24 else f"{token[:12]}...{token[-6:]} ({len(token)} digits)"
        raise ValueError(f"the integer {shown} overflows a double (numbers must be finite)") from None
    return value


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
    try:
        doc = json.loads(text, parse_constant=_finite_only, parse_int=_int_of_a_double,
                         object_pairs_hook=_no_duplicates)
    except json.JSONDecodeError as exc:
        raise error(f"{name}: line {exc.lineno} column {exc.colno}",
                    f"expected JSON, found invalid JSON ({exc.msg})") from None
    except ValueError as exc:
        raise error(name, f"expected JSON, found invalid JSON ({exc})") from None
    except RecursionError:
        raise error(name, TOO_DEEP) from None
    return doc, raw
