"""The project's functions as calls of small generated helpers (C and Python alike)."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

#: sympy function name -> helper name (the helper bodies repeat the simulator's guards).
HELPER_OF = {
    "sign": "sign",
    "Sat": "sat",
    "DeadZone": "dead_zone",
    "SymLog": "sym_log",
    "SymPow": "sym_pow",
    "GTan": "tan",
    "GAsin": "asin",
    "GAcos": "acos",
}


class HelperCalls:
    """Mixin: ``_print_<Function>`` for each of :data:`HELPER_OF`, printing a helper call.

    The printer records which helpers it used in ``helpers_used`` (so only
    those are emitted) and names them with :meth:`helper_symbol`.
    """

    helpers_used: set[str]

    def helper_symbol(self, name: str) -> str:
        """The printed name of helper ``name``."""
        raise NotImplementedError

    def _helper_call(self, name: str, args: Iterable[Any]) -> str:
        self.helpers_used.add(name)
        return f"{self.helper_symbol(name)}({', '.join(self._print(a) for a in args)})"


def _printer_method(helper: str) -> Any:
    def method(self: HelperCalls, expr: Any) -> str:
        return self._helper_call(helper, expr.args)

    method.__doc__ = f"Print as a call of the ``{helper}`` helper."
    return method


for _function, _helper in HELPER_OF.items():
    setattr(HelperCalls, f"_print_{_function}", _printer_method(_helper))
