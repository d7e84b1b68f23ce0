"""A row's simplified expression as a chain of blocks (the paper's Fig. 22).

A row of the element matrix is a chain; after simplification its expression
is still mostly one: ``a_2 sign(omega)`` is a sign block then a gain block,
``LTI(omega, G)`` one transfer-function block, ``a_15 sin(a_13 theta + a_14)``
a gain, an offset, a sine and a gain. :func:`row_chain` peels the expression
from the outside in and returns the blocks left to right. What is not a chain
(the input entering a sum twice, say) becomes one block holding the whole
function of its input. Language-neutral: the printers label the blocks.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

import sympy as sp

from edm_sym.engines.symbolic.operators import LTI, Delay, Relay

#: Stands for a block's input inside its expression (printed as a dot).
PLACEHOLDER = sp.Dummy("u", real=True)



class BlockKind(str, enum.Enum):
    """The shape of one block of a simplified row expression (not an element's kind)."""

    GAIN = "gain"
    OFFSET = "offset"
    FUNCTION = "function"
    LTI = "lti"
    DELAY = "delay"
    RELAY = "relay"
    CONSTANT = "constant"


#: The kinds of block, and what ``Block.expr`` holds for each.
BLOCK_KINDS = {
    BlockKind.GAIN: "the factor",
    BlockKind.OFFSET: "the constant added",
    BlockKind.FUNCTION: "the output in terms of PLACEHOLDER",
    BlockKind.LTI: "the transfer function G(s)",
    BlockKind.DELAY: "the delay T [s]",
    BlockKind.RELAY: "the half width of the hysteresis band",
    BlockKind.CONSTANT: "the constant output (the row ignores its input)",
}


@dataclass(frozen=True)
class Block:
    """One block of a row's chain.

    Attributes
    ----------
    kind : BlockKind
        See :data:`BLOCK_KINDS`.
    expr : sympy.Expr
        What the block is (see :data:`BLOCK_KINDS`).
    """

    kind: BlockKind
    expr: sp.Expr


def row_chain(expr: sp.Expr, u: sp.Symbol) -> tuple[Block, ...]:
    """The blocks of ``expr`` as a function of the input ``u``, left to right.

    Parameters
    ----------
    expr : sympy.Expr
        A row expression (simplified, named or numeric).
    u : sympy.Symbol
        The row's input symbol.

    Returns
    -------
    tuple of Block
        Empty when the row passes its input through unchanged.
    """
    if not expr.has(u):
        return (Block(BlockKind.CONSTANT, expr),)
    return tuple(_chain(expr, u))


def _chain(e: sp.Expr, u: sp.Symbol) -> list[Block]:
    if e == u:
        return []
    if isinstance(e, LTI):
        return _chain(e.args[0], u) + [Block(BlockKind.LTI, e.args[1])]
    if isinstance(e, Delay):
        return _chain(e.args[0], u) + [Block(BlockKind.DELAY, e.args[1])]
    if isinstance(e, Relay):
        return _chain(e.args[0], u) + [Block(BlockKind.RELAY, e.args[1])]
    if e.is_Mul:
        coeff = [f for f in e.args if not f.has(u)]
        rest = [f for f in e.args if f.has(u)]
        if len(rest) == 1 and coeff:
            return _chain(rest[0], u) + [Block(BlockKind.GAIN, sp.Mul(*coeff))]
    elif e.is_Add:
        const = [t for t in e.args if not t.has(u)]
        rest = [t for t in e.args if t.has(u)]
        if len(rest) == 1 and const:
            return _chain(rest[0], u) + [Block(BlockKind.OFFSET, sp.Add(*const))]
    else:
        inner = [a for a in e.args if a.has(u)]
        if len(inner) == 1 and not isinstance(inner[0], sp.Tuple):
            arg = inner[0]
            return _chain(arg, u) + [Block(BlockKind.FUNCTION, e.xreplace({arg: PLACEHOLDER}))]
    return [Block(BlockKind.FUNCTION, e.xreplace({u: PLACEHOLDER}))]
