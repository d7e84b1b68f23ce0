"""A table of the abstraction config (TOML) into its frozen settings object, with one-line errors."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, TypeVar

from edm_sym.core.errors import ConfigError

T = TypeVar("T")


def settings_from_table(cls: type[T], keys: Sequence[str], where: str, doc: Any) -> T:
    """Build ``cls(**doc)``, naming the file and key of any problem.

    Parameters
    ----------
    cls : type
        A frozen settings dataclass that validates itself and raises
        :class:`ConfigError` naming its field.
    keys : sequence of str
        The keys the table may hold.
    where : str
        ``"<file>: <table>"``, for messages.
    doc : mapping
        The parsed table.

    Raises
    ------
    ConfigError
        Not a table, an unknown key, or a value the settings refuse
        (``"<file>: <table>.<key>: ..."``).
    """
    if not isinstance(doc, Mapping):
        raise ConfigError(where, f"expected a table, found {type(doc).__name__}")
    for key in doc:
        if key not in keys:
            raise ConfigError(f"{where}.{key}", f"unknown key (known: {', '.join(keys)})")
    try:
        return cls(**dict(doc))
    except ConfigError as exc:
        raise ConfigError(f"{where}.{exc.where.rsplit('.', 1)[-1]}", exc.problem) from None
