"""The element matrix (paper, eq. 2, Figs. 1 and 11): genes, rows, matrix.

A row takes one selected input signal and runs it through its elements left
to right; the matrix output is the sum of the row outputs. This layer holds
genomes and their validation only: no sympy, no numerics beyond decoding.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from edm_sym.core.elements import REGISTRY, Element, ParamRange, check_range, default_ranges


@dataclass(frozen=True)
class Gene:
    """One element of a row: element ``code`` and normalised parameter ``p`` in [0, 1]."""

    code: int
    p: float

    @property
    def element(self) -> type[Element]:
        """The element class of this gene."""
        return REGISTRY[self.code]


@dataclass(frozen=True)
class Row:
    """One row: the index of its selected input and its genes, left to right."""

    input: int
    genes: tuple[Gene, ...]

    def __post_init__(self) -> None:
        object.__setattr__(self, "genes", tuple(self.genes))


@dataclass(frozen=True)
class ElementMatrix:
    """n elements per row, m rows, over named inputs.

    Parameters
    ----------
    inputs : tuple of str
        The input signal names the designer provides, in order (input codes
        are indices into this tuple).
    rows : tuple of Row
        The m rows; every row has the same number of genes n.
    """

    inputs: tuple[str, ...]
    rows: tuple[Row, ...]

    def __post_init__(self) -> None:
        object.__setattr__(self, "inputs", tuple(self.inputs))
        object.__setattr__(self, "rows", tuple(self.rows))
        if not self.rows:
            raise ValueError("matrix: expected at least one row, found 0")
        n = len(self.rows[0].genes)
        for j, row in enumerate(self.rows):
            if len(row.genes) != n:
                raise ValueError(
                    f"rows[{j}]: expected {n} elements like rows[0], found {len(row.genes)}"
                )
            if not 0 <= row.input < len(self.inputs):
                raise ValueError(
                    f"rows[{j}].input_code: expected 0-{len(self.inputs) - 1}, found {row.input}"
                )
            for i, g in enumerate(row.genes):
                if g.code not in REGISTRY:
                    raise ValueError(
                        f"rows[{j}].elements[{i}].code: {g.code} is not a known element code "
                        f"(known: {min(REGISTRY)}-{max(REGISTRY)})"
                    )
                if not 0.0 <= g.p <= 1.0:
                    raise ValueError(f"rows[{j}].elements[{i}].p: expected 0..1, found {g.p}")

    @property
    def n_elements(self) -> int:
        """Elements per row (the paper's n)."""
        return len(self.rows[0].genes)

    @property
    def n_rows(self) -> int:
        """Number of rows (the paper's m)."""
        return len(self.rows)

    @property
    def shape(self) -> str:
        """The paper's notation, ``"4x5"`` for 4 elements per row and 5 rows."""
        return f"{self.n_elements}x{self.n_rows}"


@dataclass(frozen=True)
class Compensator:
    """A matrix with what it needs to compute: sample time and parameter ranges.

    Parameters
    ----------
    matrix : ElementMatrix
    sample_time : float
        Ts [s].
    ranges : mapping of element name to ParamRange
        The ranges that decode each ``p``; missing names use the defaults for
        ``sample_time`` and ``record_length``.
    record_length : float
        T_sum [s], for the default ranges.
    """

    matrix: ElementMatrix
    sample_time: float
    ranges: Mapping[str, ParamRange]
    record_length: float = 20.0

    def __post_init__(self) -> None:
        from edm_sym.core.errors import ConfigError

        if not isinstance(self.matrix, ElementMatrix):
            raise ConfigError("matrix", f"expected an ElementMatrix (make_matrix), found "
                              f"{type(self.matrix).__name__}")
        for name in ("sample_time", "record_length"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, numbers.Real) \
                    or not math.isfinite(value) or value <= 0:
                raise ConfigError(name, f"expected a number of seconds > 0, found {value!r}")
        if not isinstance(self.ranges, Mapping) or not all(
                isinstance(r, ParamRange) for r in self.ranges.values()):
            raise ConfigError("ranges", "expected a mapping of element names to ParamRange, found "
                              f"{self.ranges!r}"[:200])
        for name, rng in self.ranges.items():
            try:
                check_range(name, rng)
            except ValueError as exc:
                raise ConfigError(f"ranges[{name!r}]", str(exc).partition(": ")[2]) from None
        try:
            full = default_ranges(self.sample_time, self.record_length)
        except ValueError as exc:  # a sample time the default ranges cannot span
            raise ConfigError("sample_time", f"expected a sample time the default parameter "
                              f"ranges fit with record_length = {self.record_length:g} s "
                              f"({exc}), found {self.sample_time:g} s") from exc
        full.update(self.ranges)
        object.__setattr__(self, "ranges", full)

    def value(self, gene: Gene) -> float | None:
        """The decoded parameter ``a`` of a gene (None for parameter-free elements)."""
        el = gene.element
        return self.ranges[el.name].decode(gene.p) if el.param is not None else None

    def row_elements(self, j: int) -> list[tuple[type[Element], float | None]]:
        """Row ``j`` as (element class, decoded parameter) pairs, left to right."""
        return [(g.element, self.value(g)) for g in self.matrix.rows[j].genes]


def make_matrix(
    inputs: Sequence[str], rows: Sequence[tuple[str | int, Sequence[tuple[str | int, float]]]]
) -> ElementMatrix:
    """Build a matrix by names, for hand-written models and tests.

    Parameters
    ----------
    inputs : sequence of str
        Input names.
    rows : sequence of (input, [(element, p), ...])
        ``input`` is a name or index; ``element`` a name or code.

    Examples
    --------
    >>> m = make_matrix(["omega"], [("omega", [("sign", 0), ("gain", 0.55)])])
    >>> m.shape
    '2x1'
    """
    from edm_sym.core.elements import element
    from edm_sym.core.errors import ConfigError

    if isinstance(inputs, str):
        raise ConfigError("inputs", f"expected a sequence of input names, found the string {inputs!r}")
    inputs = tuple(inputs)
    out = []
    for j, row in enumerate(rows):
        try:
            inp, genes = row
        except (TypeError, ValueError):
            raise ConfigError(f"rows[{j}]", f"expected (input, [(element, p), ...]), found {row!r}") from None
        if isinstance(inp, str) and inp not in inputs:
            raise ConfigError(f"rows[{j}]", f"expected one of the inputs {', '.join(inputs)}, found {inp!r}")
        if not isinstance(inp, str) and (isinstance(inp, bool) or not isinstance(inp, numbers.Integral)
                                         or not 0 <= inp < len(inputs)):
            raise ConfigError(f"rows[{j}]", f"expected an input name or an index below {len(inputs)}, "
                              f"found {inp!r}")
        made = []
        for i, gene in enumerate(genes):
            where = f"rows[{j}].elements[{i}]"
            try:
                code, p = gene
                if isinstance(code, bool) or not isinstance(code, str | numbers.Integral):
                    raise KeyError(f"{code!r} is no element name or code")
                cls = element(code)
                value = float(p)
            except KeyError as exc:
                raise ConfigError(where, str(exc.args[0])) from None
            except (TypeError, ValueError):
                raise ConfigError(where, f"expected (element name or code, p), found {gene!r}") from None
            made.append(Gene(cls.code, value))
        out.append(Row(inputs.index(inp) if isinstance(inp, str) else int(inp), tuple(made)))
    try:
        return ElementMatrix(inputs, tuple(out))
    except ValueError as exc:  # no rows, a p outside [0, 1]: named as the matrix names it
        where, _, problem = str(exc).partition(": ")
        raise ConfigError(where, problem) from None
