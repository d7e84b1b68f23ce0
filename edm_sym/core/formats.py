"""What a logger's file holds, and the part of it a data spec selects (docs/data.md#files-loggers-write).

A file is read into a tree: a MATLAB struct or an HDF5 group is a mapping of
its fields, an array a leaf. ``FILE:SEL[,SEL...]`` selects parts of it
(:func:`split_spec`): a struct (its 1-D fields become columns), a field
(``run.omega``, one column named ``omega``), or a 2-D matrix whose columns the
caller names (``names="t,ref,theta"``, a command's ``--columns``). A file read without a selection gives
its top-level 1-D arrays, as before; one whose samples sit in a matrix or a
struct is refused with what it holds and how to select it (:func:`contents`).
"""

from __future__ import annotations

import io
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from edm_sym.core.errors import DataFormatError

#: Suffixes whose files hold named arrays a spec ``FILE:SEL`` may select in.
SELECTABLE = (".mat", ".h5", ".hdf5", ".npz", ".parquet")
#: The signature of an HDF5 file; MATLAB v7.3 files carry it after a 512-byte header.
HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"
#: MATLAB classes of numeric arrays (others, such as char or cell, are skipped).
MATLAB_NUMERIC = {"double", "single", "int8", "uint8", "int16", "uint16", "int32", "uint32",
                  "int64", "uint64", "logical"}

Tree = dict[str, Any]


def split_spec(spec: str | Path) -> tuple[Path, str | None]:
    """``FILE.mat:data`` -> (``FILE.mat``, ``"data"``); a path without a selection -> (path, None).

    A spec is split at its last colon when the part before it ends in one of
    :data:`SELECTABLE` and is no existing path itself.
    """
    text = str(spec)
    head, sep, sel = text.rpartition(":")
    if sep and Path(head).suffix.lower() in SELECTABLE and not Path(text).exists():
        return Path(head), sel.strip()
    return Path(text), None


def is_hdf5(raw: bytes) -> bool:
    """An HDF5 file, or a MATLAB v7.3 file (HDF5 after a 512-byte header)."""
    return raw[:8] == HDF5_SIGNATURE or raw[512:520] == HDF5_SIGNATURE


def read_tree(name: str, raw: bytes, suffix: str) -> Tree:
    """The file's named arrays and structs as a tree (MATLAB arrays in MATLAB's orientation).

    Raises
    ------
    DataFormatError
        Unreadable data, or a format whose optional reader is not installed.
    """
    if suffix == ".npz":
        try:
            with np.load(io.BytesIO(raw), allow_pickle=False) as z:
                return {k: np.asarray(z[k]) for k in z.files}
        except Exception as exc:  # numpy raises several types for a bad archive
            raise DataFormatError(name, f"expected an .npz archive, found unreadable data ({exc})") \
                from None
    if suffix == ".parquet":
        return _parquet(name, raw)
    if suffix == ".mat" and not is_hdf5(raw):
        return _mat(name, raw)
    return _hdf5(name, raw, matlab=suffix == ".mat")


def _parquet(name: str, raw: bytes) -> Tree:
    try:
        import pyarrow.parquet as pq
    except ImportError:
        raise DataFormatError(name, "expected a reader for Parquet, found pyarrow not installed; "
                              "install the extra 'edm_sym[parquet]'") from None
    try:
        table = pq.read_table(io.BytesIO(raw))
    except Exception as exc:  # pyarrow raises several types for a bad file
        raise DataFormatError(name, f"expected a Parquet file, found unreadable data ({exc})") from None
    out: Tree = {}
    for col in table.column_names:
        values = table.column(col)
        try:
            out[col] = values.to_numpy()
        except Exception:  # nested or null-holding columns: named as what they are
            out[col] = np.asarray([str(values.type)])
    return out


def _mat(name: str, raw: bytes) -> Tree:
    from scipy import io as sio

    try:
        doc = sio.loadmat(io.BytesIO(raw))
    except Exception as exc:  # scipy raises several types for a bad file
        raise DataFormatError(name, f"expected a MATLAB .mat file, found unreadable data ({exc})") from None
    return {k: _mat_value(v) for k, v in doc.items()
            if not k.startswith("__") and isinstance(v, np.ndarray)}


def _mat_value(v: np.ndarray) -> Any:
    """A MATLAB struct (a 1x1 record array) as a mapping of its fields; any other array as is."""
    if v.dtype.names and v.size == 1:
        rec = v.reshape(-1)[0]
        return {f: _mat_value(np.asarray(rec[f])) for f in v.dtype.names}
    if v.dtype == object and v.size == 1 and isinstance(v.reshape(-1)[0], np.ndarray):
        return _mat_value(v.reshape(-1)[0])
    return v


def _hdf5(name: str, raw: bytes, *, matlab: bool) -> Tree:
    try:
        import h5py
    except ImportError:
        what = "a MATLAB v7.3 (HDF5) file" if matlab else "an HDF5 file"
        raise DataFormatError(name, f"expected a file scipy can read, found {what}; install the "
                              f"extra 'edm_sym[mat73]' (h5py) to read it") from None

    def walk(group: Any) -> Tree:
        out: Tree = {}
        for key in group:
            obj = group[key]
            if key.startswith("#"):
                continue
            if isinstance(obj, h5py.Group):
                out[key] = walk(obj)
                continue
            cls = obj.attrs.get("MATLAB_class", b"double" if matlab else b"")
            cls = cls.decode() if isinstance(cls, bytes) else str(cls)
            if matlab and cls not in MATLAB_NUMERIC:
                continue
            value = np.asarray(obj[()])
            # MATLAB writes column-major: an N x 1 column is stored as 1 x N.
            out[key] = value.T if matlab else value
        return out

    try:
        with h5py.File(io.BytesIO(raw), "r") as f:
            return walk(f)
    except (OSError, ValueError) as exc:
        what = "a MATLAB v7.3 (HDF5) file" if matlab else "an HDF5 file"
        raise DataFormatError(name, f"expected {what}, found unreadable data ({exc})") from None


def describe(value: Any) -> str:
    """What a tree node is, for messages: ``a 20000x7 matrix``, ``a struct (t, omega)``."""
    if isinstance(value, Mapping):
        return f"a struct ({', '.join(value) or 'empty'})"
    arr = np.asarray(value)
    if not np.issubdtype(arr.dtype, np.number) or np.iscomplexobj(arr):
        return f"an array of {arr.dtype} of shape {arr.shape}"
    if arr.size == 1:
        return "a scalar"
    if arr.ndim == 1 or (arr.ndim == 2 and 1 in arr.shape):
        return f"{arr.size} samples"
    return "a " + "x".join(map(str, arr.shape)) + (" matrix" if arr.ndim == 2 else " array")


def is_matrix(value: Any) -> bool:
    """A numeric array of two dimensions, neither of them 1 (columns of samples side by side)."""
    if isinstance(value, Mapping):
        return False
    arr = np.asarray(value)
    return (arr.ndim == 2 and 1 not in arr.shape and np.issubdtype(arr.dtype, np.number)
            and not np.iscomplexobj(arr))


def contents(tree: Tree) -> str:
    """Every top-level entry and what it is: ``data (a 20000x7 matrix), Iz (a scalar)``."""
    return ", ".join(f"{k} ({describe(v)})" for k, v in tree.items()) or "nothing"


def selection_hint(file: str, tree: Tree) -> str:
    """How to select the matrices and structs of a file (empty when it has none)."""
    hints = []
    for key, value in tree.items():
        if is_matrix(value):
            k = min(np.shape(value))
            hints.append(f"{file}:{key} with names=\"NAME,NAME,...\" ({k} names)")
        elif isinstance(value, Mapping) and value:
            hints.append(f"{file}:{key} (its fields) or {file}:{key}.FIELD")
    return "; select " + " or ".join(hints) if hints else ""


def select(name: str, file: str, tree: Tree, selection: str, names: Sequence[str] | None
           ) -> Tree:
    """The arrays a selection ``SEL[,SEL...]`` names, flat: column name -> array.

    A struct gives its fields, a 1-D array one column named by its last part,
    a matrix its columns named by ``names`` (rows are samples; a matrix of
    ``len(names)`` rows is read transposed).

    Raises
    ------
    DataFormatError
        An unknown part (listing what the struct holds), a matrix without
        names or with another number of them, names given for no matrix.
    """
    out: Tree = {}
    parts = [p.strip() for p in selection.split(",")]
    used_names = False
    for part in parts:
        if not part:
            raise DataFormatError(name, f"expected FILE:NAME[,NAME...] after {file}, found an empty "
                                  "selection")
        node: Any = tree
        path = [p for p in part.replace("/", ".").split(".") if p]
        for k, key in enumerate(path):
            if not isinstance(node, Mapping) or key not in node:
                at = ".".join(path[:k]) or file
                have = contents(node) if isinstance(node, Mapping) else describe(node)
                raise DataFormatError(f"{file}:{part}", f"expected {key!r} in {at}, found only: "
                                      f"{have}")
            node = node[key]
        label = path[-1] if path else file
        if isinstance(node, Mapping):
            out.update(node)
        elif is_matrix(node):
            if names is None:
                raise DataFormatError(f"{file}:{part}", f"expected the names of the columns of "
                                      f"{describe(node)} (names=\"NAME,NAME,...\"), found none")
            out.update(_matrix_columns(f"{file}:{part}", np.asarray(node), names))
            used_names = True
        else:
            out[label] = node
    if names is not None and not used_names:
        raise DataFormatError("names", f"expected a matrix selected to name the columns of "
                              f"({file}:NAME), found {selection!r}")
    return out


def _matrix_columns(where: str, arr: np.ndarray, names: Sequence[str]) -> Tree:
    k = len(names)
    if len(set(names)) != k:
        twice = next(n for n in names if list(names).count(n) > 1)
        raise DataFormatError("names", f"expected unique names, found {twice!r} twice")
    if arr.shape[1] == k:
        cols = arr.T
    elif arr.shape[0] == k:
        cols = arr
    else:
        raise DataFormatError(where, f"expected {k} columns as `names` names, found "
                              f"{describe(arr)}")
    return {n: np.ascontiguousarray(c) for n, c in zip(names, cols, strict=True)}


def parse_names(text: str | Sequence[str] | None, where: str = "names") -> tuple[str, ...] | None:
    """The column names of a matrix: ``"t,ref,theta"`` or a list of them (None: not given).

    ``where`` names them in messages: the parameter ``names`` of :func:`edm_sym.load_data`
    (a command's ``--columns``).

    Raises
    ------
    DataFormatError
        An empty name.
    """
    if text is None:
        return None
    items = [s.strip() if isinstance(s, str) else s
             for s in (text.split(",") if isinstance(text, str) else text)]
    if not items or not all(isinstance(s, str) and s for s in items):
        raise DataFormatError(where, f"expected comma-separated column names, found {text!r}")
    return tuple(items)
