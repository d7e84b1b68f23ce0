"""What the C and Python printers share: helper calls, and a stage's lines by its realisation."""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import Any

from edm_sym.core.elements.realisation import dispatch

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

    def helpers_wanted(self, names: Iterable[str] | None,
                       table: Mapping[str, tuple[Any, ...]]) -> set[str]:
        """``names`` (default: those used) with every helper they call, from ``table``.

        ``table[name][0]`` lists the helpers that ``name`` calls.

        Raises
        ------
        ValueError
            On a name ``table`` does not hold.
        """
        wanted = set(self.helpers_used if names is None else names)
        unknown = wanted - set(table)
        if unknown:
            raise ValueError(f"helpers: unknown {sorted(unknown)} (known: {sorted(table)})")
        todo = list(wanted)
        while todo:
            for dep in table[todo.pop()][0]:
                if dep not in wanted:
                    wanted.add(dep)
                    todo.append(dep)
        return wanted

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


class StageLines:
    """Mixin: one sample of a stage as statements, chosen by the type of its realisation.

    :meth:`stage_lines` calls ``_stage_<RealisationType>`` (as SymPy's printers
    call ``_print_<Class>``); those call the printer's own statement methods
    (``assign``, ``linear_lines``, ``delay_lines``, ``relay_lines``), which hold
    the language's syntax. A new stage kind adds one ``_stage_`` method here.
    """

    def assign(self, var: str, expr: Any) -> list[str]:
        """``var = expr`` in the target language."""
        raise NotImplementedError

    def linear_lines(self, b: Sequence[float], a: Sequence[float], z: str,
                     x: str = "x") -> list[str]:
        """One sample of a direct form II transposed filter."""
        raise NotImplementedError

    def delay_lines(self, samples: int, buf: str, pos: str | None, x: str = "x") -> list[str]:
        """One sample of a ring-buffer delay."""
        raise NotImplementedError

    def relay_lines(self, threshold: float, out: str, x: str = "x") -> list[str]:
        """One sample of the relay with hysteresis."""
        raise NotImplementedError

    def stage_lines(self, stage: Any, state: Mapping[str, str]) -> list[str]:
        """The statements of one sample of ``stage`` on the variable ``x``.

        Parameters
        ----------
        stage : Stage
            A stage of the symbolic model (its realisation and expression).
        state : mapping of str to str
            The lvalue of each state part, by the realisation's suffix
            (``"z"``, ``"buf"``, ``"pos"``, ``"out"``).

        Returns
        -------
        list of str
        """
        return dispatch(self, "_stage_", stage.realisation)(stage, state)

    def _stage_StaticMap(self, stage: Any, state: Mapping[str, str]) -> list[str]:  # noqa: N802
        return self.assign("x", stage.numeric_expr())

    def _stage_LinearFilter(self, stage: Any, state: Mapping[str, str]) -> list[str]:  # noqa: N802
        r = stage.realisation
        return self.linear_lines(r.b, r.a, state["z"])

    def _stage_DelayLine(self, stage: Any, state: Mapping[str, str]) -> list[str]:  # noqa: N802
        return self.delay_lines(stage.realisation.samples, state["buf"], state.get("pos"))

    def _stage_Relay(self, stage: Any, state: Mapping[str, str]) -> list[str]:  # noqa: N802
        return self.relay_lines(stage.realisation.threshold, f"{state['out']}[0]")
