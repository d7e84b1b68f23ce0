"""The one frozen symbolic model between decoding and every output.

:func:`build_model` turns a compensator into rows of :class:`Stage` objects,
one per element, each carrying exactly what every exporter needs: the named
parameter symbol and its value, the static expression, the continuous transfer
function and the discrete coefficients the simulator uses, the delay length or
the relay threshold. Printers and templates read this model; nobody re-decodes.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import sympy as sp

from edm_sym.core.elements import Element, LinearElement, ParamRange, StaticElement
from edm_sym.core.elements.realisation import DelayLine, LinearFilter, Realisation, Relay
from edm_sym.core.matrix import Compensator
from edm_sym.engines.symbolic.functions import SYMPY_OPS

#: The Laplace variable.
s = sp.Symbol("s")
#: Placeholder for a stage's input in its own expression.
X = sp.Symbol("x", real=True)


@dataclass(frozen=True)
class ParamInfo:
    """A named parameter a_k (numbered as the paper's Table II: k = j n + i + 1)."""

    symbol: sp.Symbol
    value: float
    p: float
    range: ParamRange
    unit: str
    meaning: str
    element: str
    row: int
    col: int


@dataclass(frozen=True)
class Stage:
    """One element of a row, decoded.

    Attributes
    ----------
    col : int
        Column index (0-based, left to right).
    element : type[Element]
        The element class.
    realisation : Realisation
        What it computes in discrete time (:mod:`edm_sym.core.elements.realisation`):
        the simulator's coefficients, delay or threshold. Exporters dispatch on
        its type.
    param : ParamInfo or None
    expr : sympy.Expr or None
        Static stages: the output in terms of :data:`X` and the parameter symbol.
    tf : tuple of (num, den) or None
        Linear stages: continuous coefficient lists in s with the parameter symbol.
    """

    col: int
    element: type[Element]
    realisation: Realisation
    param: ParamInfo | None
    expr: sp.Expr | None = None
    tf: tuple[tuple[Any, ...], tuple[Any, ...]] | None = None

    @property
    def kind(self) -> str:
        """The stage kind's readable name (``"static"``, ``"linear"``, ...), for people."""
        return self.realisation.kind

    @property
    def b(self) -> tuple[float, ...]:
        """A filter's numerator coefficients (z^-1 powers); empty for other stages."""
        r = self.realisation
        return r.b if isinstance(r, LinearFilter) else ()

    @property
    def a(self) -> tuple[float, ...]:
        """A filter's denominator coefficients (z^-1 powers, ``a[0] == 1``); else empty."""
        r = self.realisation
        return r.a if isinstance(r, LinearFilter) else ()

    @property
    def method(self) -> str | None:
        """A filter's discretisation; None for other stages."""
        r = self.realisation
        return r.method if isinstance(r, LinearFilter) else None

    @property
    def delay(self) -> int:
        """A delay's length in samples; 0 for other stages."""
        r = self.realisation
        return r.samples if isinstance(r, DelayLine) else 0

    @property
    def threshold(self) -> float | None:
        """A relay's switching threshold; None for other stages."""
        r = self.realisation
        return r.threshold if isinstance(r, Relay) else None

    @property
    def value(self) -> float | None:
        """The numeric parameter value (None when parameter-free)."""
        return None if self.param is None else self.param.value

    def numeric_expr(self) -> sp.Expr | None:
        """The static expression with the parameter's value substituted."""
        if self.expr is None:
            return None
        if self.param is None:
            return self.expr
        return self.expr.subs(self.param.symbol, sp.Float(self.param.value, 17))

    def numeric_tf(self) -> tuple[list[Any], list[Any]]:
        """A linear stage's continuous coefficients with the parameter's value substituted."""
        num, den = self.tf
        if self.param is None:
            return list(num), list(den)
        sub = {self.param.symbol: sp.Float(self.param.value, 17)}
        return ([sp.sympify(c).xreplace(sub) for c in num],
                [sp.sympify(c).xreplace(sub) for c in den])


@dataclass(frozen=True)
class RowModel:
    """One row of the model: its input, its stages and (decoded) its expressions.

    :func:`build_model` gives rows with the first five fields (what the code
    printers need); :func:`edm_sym.engines.symbolic.decode` makes new rows with every
    field (the others keep their defaults in a stages-only model).

    Attributes
    ----------
    index : int
        Row number, 0-based.
    input, input_symbol : str, sympy.Symbol
        The row's selected input.
    stages : tuple of Stage
        Left to right.
    role : str or None
        The input's physical role (``"velocity"``, ``"acceleration"``,
        ``"angle"``, ``"angle_wrapped"``) or None.
    expr_raw, expr_raw_numeric : sympy.Expr or None
        The stages composed as they are, with the ``a_k`` symbols / with numbers;
        dynamic stages are the operators ``LTI``, ``Delay``, ``Relay``
        (:mod:`edm_sym.engines.symbolic.operators`).
    expr, expr_numeric : sympy.Expr or None
        The same after the bounded simplification passes.
    terms : tuple of PhysicalTerm
        The physical terms of ``expr_numeric`` (:mod:`edm_sym.engines.symbolic.classify`).
    linear_parts : tuple of LinearPart
        Each filter or delay stage as python-control transfer functions
        (continuous, and discrete with the simulator's coefficients).
    system : control.NonlinearIOSystem or None
        The whole row as a discrete python-control system (dt = Ts).
    """

    index: int
    input: str
    input_symbol: sp.Symbol
    stages: tuple[Stage, ...]
    extra: dict[str, Any] = field(default_factory=dict, compare=False)
    role: str | None = None
    expr_raw: sp.Expr | None = None
    expr_raw_numeric: sp.Expr | None = None
    expr: sp.Expr | None = None
    expr_numeric: sp.Expr | None = None
    terms: tuple[Any, ...] = ()
    linear_parts: tuple[Any, ...] = field(default=(), compare=False)
    system: Any = field(default=None, compare=False)


@dataclass(frozen=True)
class SymbolicModel:
    """The decoded compensator.

    Attributes
    ----------
    compensator : Compensator
    inputs : tuple of str
    input_symbols : tuple of sympy.Symbol
    sample_time : float
    rows : tuple of RowModel
    params : tuple of ParamInfo
        Every named parameter, in a_k order.
    source_sha256 : str or None
        The sha256 of the result file decoded.
    target : str or None
        The name of the target column.
    roles : dict of str to str or None
        The physical role of each input (filled by :func:`edm_sym.engines.symbolic.decode`).
    axis : str
        ``"rotary"`` or ``"linear"``: the SI units of the terms and of every
        output (``edm_sym.core.units.axis_units(model.axis)``).
    """

    compensator: Compensator
    inputs: tuple[str, ...]
    input_symbols: tuple[sp.Symbol, ...]
    sample_time: float
    rows: tuple[RowModel, ...]
    params: tuple[ParamInfo, ...]
    source_sha256: str | None = None
    target: str | None = None
    roles: dict[str, str | None] = field(default_factory=dict, compare=False)
    axis: str = "rotary"

    def __repr__(self) -> str:
        """A header line and one line per row: its simplified expression with numbers.

        A model from :func:`build_model` (no expressions yet) shows each row's
        elements and values instead.
        """
        from edm_sym.core.display import matrix_lines

        head = (f"SymbolicModel({len(self.rows)} rows, inputs {', '.join(self.inputs)}, "
                f"Ts = {self.sample_time:g} s" + (f", target {self.target!r}" if self.target else "")
                + ")")
        if any(r.expr_numeric is None for r in self.rows):
            return "\n".join([head] + [f"  {line}" for line in matrix_lines(self.compensator)])
        lines = [head]
        for r in self.rows:
            short = r.expr_numeric.xreplace({f: sp.Float(f, 4) for f in r.expr_numeric.atoms(sp.Float)})
            lines.append(f"  row {r.index + 1} ({r.input}): {sp.sstr(short, full_prec=False)}")
        return "\n".join(lines)

    def _repr_latex_(self) -> str | None:
        """The compensator as LaTeX, one row per line, for Jupyter (the report's printer)."""
        from edm_sym.core.display import latex_repr

        return latex_repr("model", self)

    def total(self, *, numeric: bool = True, simplified: bool = True) -> sp.Expr:
        """The compensation torque: the sum of the row expressions (after decoding).

        Parameters
        ----------
        numeric : bool, default True
            Numbers instead of the ``a_k`` symbols.
        simplified : bool, default True
            The simplified rows instead of the raw ones.

        Returns
        -------
        sympy.Expr
        """
        name = ("expr" if simplified else "expr_raw") + ("_numeric" if numeric else "")
        parts = [getattr(r, name) for r in self.rows]
        if any(p is None for p in parts):
            raise ValueError("total: the rows have no expressions yet; use "
                             "edm_sym.engines.symbolic.decode, not build_model")
        return sp.Add(*parts)

    def to_control(self, *, output: str = "tau_cmp", name: str | None = None) -> Any:
        """The whole compensator as a discrete python-control system (``dt = Ts``).

        Parameters
        ----------
        output : str, default "tau_cmp"
            The output's name.
        name : str, optional
            The system's name (default ``"edm_compensator"``).

        Returns
        -------
        control.NonlinearIOSystem
            Inputs named as the model's inputs (all of them, in order; an input
            no row reads is ignored), one output, the rows' states from rest;
            :func:`control.input_output_response` equals the reference
            simulator (docs/symbolic.md#python-control). It goes into a loop
            with :func:`control.interconnect`, connected by signal names.

        Examples
        --------
        >>> sys = edm_sym.decode(result).to_control()          # doctest: +SKIP
        >>> resp = control.input_output_response(sys, t, u)    # doctest: +SKIP
        """
        from edm_sym.engines.symbolic.lti import compensator_system

        return compensator_system(self, output=output, name=name)


def _stage(comp: Compensator, j: int, i: int) -> Stage:
    gene = comp.matrix.rows[j].genes[i]
    el = gene.element
    n = comp.matrix.n_elements
    info = None
    if el.param is not None:
        k = j * n + i + 1  # the paper's address alpha = j n + i + 1 (eq. 1)
        info = ParamInfo(
            symbol=sp.Symbol(f"a_{k}", real=True), value=float(comp.value(gene)), p=gene.p,
            range=comp.ranges[el.name], unit=el.param.unit, meaning=el.param.meaning,
            element=el.name, row=j, col=i,
        )
    a_sym = info.symbol if info else None
    realisation = el.realise(info.value if info else None, comp.sample_time)
    expr = tf = None
    # The sympy forms come from the element class (a declaration), not from a stage kind.
    if issubclass(el, StaticElement):
        expr = sp.sympify(el.f(SYMPY_OPS, X, a_sym))
    elif issubclass(el, LinearElement):
        num, den = el.tf(a_sym)
        tf = (tuple(sp.sympify(c) for c in num), tuple(sp.sympify(c) for c in den))
    return Stage(i, el, realisation, info, expr=expr, tf=tf)


def build_model(comp: Compensator, *, sha256: str | None = None,
                target: str | None = None, axis: str = "rotary") -> SymbolicModel:
    """Decode a compensator into its stages (no simplification).

    Parameters
    ----------
    comp : Compensator
    sha256 : str, optional
        Digest of the result file, carried for the exports' headers.
    target : str, optional
        Name of the target column.
    axis : str
        ``"rotary"`` or ``"linear"`` (the result's ``axis``), for the units outputs print.
    """
    syms = tuple(sp.Symbol(name, real=True) for name in comp.matrix.inputs)
    rows = []
    params = []
    for j, row in enumerate(comp.matrix.rows):
        stages = tuple(_stage(comp, j, i) for i in range(len(row.genes)))
        params += [st.param for st in stages if st.param is not None]
        rows.append(RowModel(j, comp.matrix.inputs[row.input], syms[row.input], stages))
    return SymbolicModel(comp, comp.matrix.inputs, syms, comp.sample_time, tuple(rows),
                         tuple(params), sha256, target, axis=axis)
