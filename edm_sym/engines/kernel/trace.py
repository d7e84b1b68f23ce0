"""Rows as steps: a realisation, or a static element traced through the math interface.

A :class:`~edm_sym.core.elements.realisation.StaticMap` becomes the steps its
element's ``f`` performs, found by calling ``f`` on a tracer
(:class:`TraceOps`, a third implementation of the math interface of
:mod:`edm_sym.core.elements.ops`), so elements are still defined once; a
:class:`LinearFilter`, :class:`DelayLine` or :class:`Relay` becomes one step
with its coefficients, length or threshold. A step is a compiled instruction
``(op, i1, r1, r2, coefficients)`` or a numpy step ``(method, numbers)`` of
the math interface. Each consumer dispatches on the realisation's type
(``_encode_<Type>``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from edm_sym.core.elements.realisation import (
    DelayLine,
    LinearFilter,
    Realisation,
    Relay,
    StaticMap,
    dispatch,
)
from edm_sym.engines.kernel.loops import (
    ADD,
    CONST,
    DEAD_ZONE,
    DELAY,
    FIR,
    LFILTER,
    LOWER,
    MUL,
    NEG,
    RELAY,
    SAT,
    SIGN,
)

__all__ = ["COMPILED", "TRACE", "TraceOps", "encode", "gene_encoder"]

#: Methods of the math interface the kernel compiles (exact arithmetic, limits,
#: signs). The others (sin, tan, log ...) stay numpy steps: the C library's
#: functions over the whole signal (:data:`edm_sym.engines.kernel.program.CALLS`),
#: so their bits are the reference simulator's.
COMPILED = {"neg": NEG, "add": ADD, "mul": MUL, "const": CONST, "sign": SIGN, "sat": SAT,
            "lower_limit": LOWER, "dead_zone": DEAD_ZONE}


class _Signal:
    """A traced signal: the steps (math-interface method, numbers) applied so far."""

    __slots__ = ("steps",)

    def __init__(self, steps: tuple = ()):
        self.steps = steps

    def then(self, name: str, *args: Any) -> _Signal:
        return _Signal((*self.steps, (name, tuple(_number(c) for c in args))))

    def __neg__(self) -> _Signal:
        return self.then("neg")

    def __add__(self, c: float) -> _Signal:
        return self.then("add", c)

    __radd__ = __add__

    def __sub__(self, c: float) -> _Signal:
        return self.then("add", -_number(c))  # x - c is x + (-c) to the bit

    def __mul__(self, c: float) -> _Signal:
        return self.then("mul", c)

    __rmul__ = __mul__


class _Param:
    """The parameter ``a`` times a number, while a static element's template is traced."""

    __slots__ = ("k",)

    def __init__(self, k: float = 1.0):
        self.k = k

    def __neg__(self) -> _Param:
        return _Param(-self.k)

    def __mul__(self, c: Any) -> Any:
        if isinstance(c, int | float) and not isinstance(c, bool):
            return _Param(self.k * c)
        return NotImplemented

    __rmul__ = __mul__

    def __float__(self) -> float:
        raise TypeError("the template needs a's value")


def _number(c: Any) -> float | _Param:
    if isinstance(c, _Param):
        return c
    if isinstance(c, _Signal) or not isinstance(c, int | float | np.floating | np.integer):
        raise TypeError(f"the kernel traces functions of one signal and numbers, found {c!r}")
    return float(c)


def _traced(name: str) -> Any:
    def method(x: _Signal, *args: float) -> _Signal:
        if not isinstance(x, _Signal):
            raise TypeError(f"the kernel traces functions of one signal, found {name}({x!r})")
        return x.then(name, *args)

    method.__name__ = name
    return staticmethod(method)


class TraceOps:
    """The math interface (:mod:`edm_sym.core.elements.ops`) recording the steps.

    A static element's ``f(TRACE, x, a)`` with ``x`` a traced signal returns
    the signal with the steps ``f`` applies, each a method of the interface
    and its numbers.
    """

    pi = math.pi


for _name in ("sin", "atan", "tanh", "sign", "sat", "lower_limit", "dead_zone", "sym_log",
              "sym_pow", "tan", "asin", "acos"):
    setattr(TraceOps, _name, _traced(_name))

TRACE = TraceOps()



class _Encoder:
    """The steps of one realisation, by its type: compiled ``(op, i1, r1, r2, coef)``
    tuples and numpy ``(name, args)`` pairs."""

    def __init__(self) -> None:
        self.items: list[tuple] = []

    def _encode_StaticMap(self, r: StaticMap) -> None:  # noqa: N802
        template = _template(r.element)
        if template is not None and r.a is not None:
            a = float(r.a)
            self.items.extend(_instance(template, a))
            return
        y = r.element.f(TRACE, _Signal(), r.a)
        self.items.extend(_items(y))

    def _encode_LinearFilter(self, r: LinearFilter) -> None:  # noqa: N802
        self.items.extend(_linear_items(r.b, r.a))

    def _encode_DelayLine(self, r: DelayLine) -> None:  # noqa: N802
        self.items.append((DELAY, r.samples, 0.0, 0.0, ()))

    def _encode_Relay(self, r: Relay) -> None:  # noqa: N802
        self.items.append((RELAY, 0, r.threshold, 0.0, ()))


def _items(y: Any) -> list[tuple]:
    """The steps of a traced output as encoder items."""
    if not isinstance(y, _Signal):  # a constant output
        return [(CONST, 0, _number(y), 0.0, ())]
    out = []
    for name, args in y.steps:
        op = COMPILED.get(name)
        if op is None:
            out.append((name, args))
        else:
            out.append((op, 0, args[0] if args else 0.0, args[1] if len(args) > 1 else 0.0, ()))
    return out


_TEMPLATES: dict[type, list | None] = {}


def _template(element: type) -> list | None:
    """A static element traced once with a symbolic ``a`` (None: trace each value instead)."""
    if element not in _TEMPLATES:
        try:
            items = _items(element.f(TRACE, _Signal(), _Param()))
        except TypeError:
            items = None
        _TEMPLATES[element] = items
    return _TEMPLATES[element]


def _value(v: Any, a: float) -> Any:
    if isinstance(v, _Param):
        return a if v.k == 1.0 else (-a if v.k == -1.0 else v.k * a)
    return v


def _instance(template: list, a: float) -> list[tuple]:
    out = []
    for item in template:
        if len(item) == 2:
            name, args = item
            out.append((name, tuple([_value(v, a) for v in args]) if args else ()))
        else:
            op, i1, r1, r2, c = item
            out.append((op, i1, _value(r1, a), _value(r2, a), c))
    return out


def _linear_items(r_b: Sequence[float], r_a: Sequence[float]) -> tuple:
    # A pure FIR (a derivative) as the reference runs it: without the a terms.
    op = LFILTER if any(r_a[1:]) else FIR
    return ((op, len(r_a) - 1, 0.0, 0.0, (*r_b, *r_a[1:])),)


def gene_encoder(element: type, ts: float, probe: float | None) -> Any:
    """A function ``a -> steps`` of one element class (what :func:`encode` gives, faster).

    The class's realisation type, found once with the parameter ``probe``,
    picks the way: a parameter-free element's steps are found once, a
    static map instantiates its traced template, a linear
    filter discretises the transfer function straight into its coefficients
    (skipping the realisation object), anything else encodes the realisation.
    """
    stage = element.realise(probe, ts)
    kind = type(stage)
    if element.param is None:  # one realisation whatever a: its steps, once
        steps = encode(stage)
        return lambda a: steps
    if kind is StaticMap:
        template = _template(element)
        if template is not None and probe is not None:
            return lambda a: tuple(_instance(template, float(a)))
    if kind is LinearFilter:
        def linear(a: float) -> tuple:
            b, den = element.coefficients(a, ts)
            return _linear_items(b.tolist(), den.tolist())

        return linear
    return lambda a: encode(element.realise(a, ts))


def encode(stage: Realisation) -> tuple:
    """The steps of one stage (a realisation), for
    :func:`~edm_sym.engines.kernel.program.compile_steps`; () changes nothing.

    Raises
    ------
    TypeError
        When a static element's function is not one of a signal and numbers.
    """
    enc = _Encoder()
    dispatch(enc, "_encode_", stage)(stage)
    return tuple(enc.items)

