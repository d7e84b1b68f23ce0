"""Bounded simplification of row expressions: a fixed number of rewrite passes.

Nothing here calls :func:`sympy.simplify`: its run time on a deeply nested
nonlinear row has no bound. Instead each pass walks the expression once,
bottom up, and applies

* sympy's own automatic evaluation (through elements vanish, chains of gains,
  offsets and inversions fold, ``sign(sign(x)) = sign(x)``, ``sign(c x) = sign(x)``
  for ``c > 0`` -- parameters whose range is positive are given that assumption
  for the pass);
* distribution of constant factors over sums (``expand_mul``, one level);
* the custom rules below, each exact for the element definitions (the guards
  of :mod:`edm_sym.core.elements.ops` included):

  - ``sign``, ``tanh``, ``atan``, ``Sat``, ``SymLog``, ``SymPow``, ``GAsin`` keep
    the sign of their argument: ``sign(f(x)) = sign(x)``;
  - an odd function of ``c sign(x)`` is ``f(c) sign(x)`` (also for a relay);
  - a guard whose argument provably stays inside it vanishes
    (``Sat(tanh(x), -2, 2) = tanh(x)``, ``GAsin(sin x) = asin(sin x)``, nested
    saturations merge, ``GTan(atan y) = Sat(y, -TAN_LIMIT, TAN_LIMIT)``);
  - constant gains move into transfer functions, consecutive ``LTI`` merge
    into one transfer function, poles and zeros that coincide (relative
    tolerance ``pz_tol``) cancel, and a constant transfer function is a gain;
  - delays commute with gains, with transfer functions and with every static
    function that maps 0 to 0, so they move outwards and merge;
  - ``Relay(c x, a) = sign(c) Relay(x, a/|c|)``.

The simplified forms are exact in continuous time; the discrete realisations
of the stages (what the simulator runs) stay in the model unchanged.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass

import numpy as np
import sympy as sp

from edm_sym.core.elements.ops import POW_INPUT_LIMIT, TAN_LIMIT
from edm_sym.engines.symbolic.functions import DeadZone, GAcos, GAsin, GTan, Sat, SymLog, SymPow
from edm_sym.engines.symbolic.operators import LTI, Delay, Relay, rational, s


@dataclass(frozen=True)
class SimplifyOptions:
    """Options of the bounded simplification.

    Parameters
    ----------
    passes : int, default 6
        The maximum number of rewrite passes (it stops earlier at a fixed point).
    pz_tol : float, default 1e-6
        A pole and a zero closer than ``pz_tol * max(|pole|, |zero|)`` cancel
        (numeric forms only; the named forms cancel exactly).
    """

    passes: int = 6
    pz_tol: float = 1e-6

    def __post_init__(self) -> None:
        if not (isinstance(self.passes, int) and 1 <= self.passes <= 100):
            raise ValueError(f"passes: expected an integer in 1..100, found {self.passes!r}")
        if not (math.isfinite(self.pz_tol) and 0 <= self.pz_tol < 1):
            raise ValueError(f"pz_tol: expected 0 <= pz_tol < 1, found {self.pz_tol!r}")


@dataclass(frozen=True)
class _Context:
    signals: frozenset[sp.Symbol]
    numeric: bool
    pz_tol: float

    def constant(self, e: sp.Expr) -> bool:
        """True when ``e`` depends on no input signal (parameters are constants)."""
        return not (e.free_symbols & self.signals) and not e.has(LTI, Delay, Relay)


def simplify_expression(
    expr: sp.Expr,
    signals: Iterable[sp.Symbol],
    *,
    numeric: bool,
    signs: Mapping[sp.Symbol, int] | None = None,
    options: SimplifyOptions | None = None,
) -> sp.Expr:
    """Simplify a row expression with a bounded number of rewrite passes.

    Parameters
    ----------
    expr : sympy.Expr
        A row expression (see :mod:`edm_sym.engines.symbolic.rowexpr`).
    signals : iterable of sympy.Symbol
        The input symbols (everything else free, except s, is a constant).
    numeric : bool
        True for the form with numbers: constant subexpressions are evaluated
        and transfer functions are normalised and cancelled numerically.
    signs : mapping of sympy.Symbol to {1, -1}, optional
        Parameters known to be positive (1) or negative (-1) from their ranges.
    options : SimplifyOptions, optional

    Returns
    -------
    sympy.Expr
    """
    opts = options or SimplifyOptions()
    ctx = _Context(frozenset(signals), numeric, opts.pz_tol)
    to_assumed, back = _assumed_symbols(signs or {})
    out = expr.xreplace(to_assumed) if to_assumed else expr
    for _ in range(opts.passes):
        new = _rewrite(out, ctx, {})
        if new == out:
            break
        out = new
    return out.xreplace(back) if back else out


def _assumed_symbols(
    signs: Mapping[sp.Symbol, int],
) -> tuple[dict[sp.Symbol, sp.Symbol], dict[sp.Symbol, sp.Symbol]]:
    fwd: dict[sp.Symbol, sp.Symbol] = {}
    for sym, sg in signs.items():
        if sg > 0:
            fwd[sym] = sp.Symbol(sym.name, positive=True)
        elif sg < 0:
            fwd[sym] = sp.Symbol(sym.name, negative=True)
    return fwd, {v: k for k, v in fwd.items()}


# -- the walk -------------------------------------------------------------------


def _rewrite(e: sp.Expr, ctx: _Context, memo: dict[sp.Expr, sp.Expr]) -> sp.Expr:
    if e.is_Atom:
        return e
    if e in memo:
        return memo[e]
    if isinstance(e, LTI):
        # The transfer function is rewritten by the LTI rule, never expanded.
        new = LTI(_rewrite(e.args[0], ctx, memo), e.args[1])
    else:
        args = tuple(_rewrite(a, ctx, memo) for a in e.args)
        new = e.func(*args) if args != e.args else e
    if ctx.numeric:
        new = fold_constants(new)
    for cls, rule in _RULES:
        if isinstance(new, cls):
            ruled = rule(new, ctx)
            if ruled is not new and ctx.numeric:
                ruled = fold_constants(ruled)
            new = ruled
            break
    if isinstance(new, sp.Function) and not isinstance(new, (LTI, Delay)):
        new = _delay_outwards(new, ctx)
    memo[e] = new
    return new


def fold_constants(e: sp.Expr) -> sp.Expr:
    """Evaluate every constant subexpression to a Float (numeric forms).

    ``evalf`` alone leaves the project's functions unevaluated
    (``Sat(-5.0*sin(1), ...)``); rebuilding them from evaluated arguments
    lets their own ``eval`` compute the number, with the simulator's guard.
    """
    if e.is_Number:
        return e
    if e.is_NumberSymbol:
        return e.evalf(17)
    if e.is_Atom:
        return e
    args = tuple(fold_constants(a) for a in e.args)
    new = e.func(*args) if args != e.args else e
    if not new.is_Number and not new.free_symbols:
        new = new.evalf(17)
    return new


# -- bounds ---------------------------------------------------------------------

_FIXED = {
    sp.sign: (-1.0, 1.0), Relay: (-1.0, 1.0), sp.tanh: (-1.0, 1.0), sp.sin: (-1.0, 1.0),
    sp.atan: (-math.pi / 2, math.pi / 2), GAsin: (-math.pi / 2, math.pi / 2),
    sp.asin: (-math.pi / 2, math.pi / 2), GAcos: (0.0, math.pi), sp.acos: (0.0, math.pi),
}
_INCREASING = (sp.tanh, sp.atan, sp.sign, Sat, SymPow, SymLog, DeadZone, GAsin, sp.asin)
_DECREASING = (GAcos, sp.acos)


def _num(e: sp.Expr) -> float | None:
    if e.is_Number:
        return float(e)
    return None


def bounds(e: sp.Expr) -> tuple[float, float] | None:
    """An interval that certainly holds every value of ``e``, or None when unknown.

    Parameters
    ----------
    e : sympy.Expr

    Returns
    -------
    tuple of float or None
    """
    v = _num(e)
    if v is not None:
        return (v, v)
    if e.is_Mul:
        c, rest = e.as_coeff_Mul()
        b = bounds(rest) if c != 1 else None
        if b is None or not c.is_Number:
            return None
        lo, hi = float(c) * b[0], float(c) * b[1]
        return (min(lo, hi), max(lo, hi))
    if e.is_Add:
        lo = hi = 0.0
        for a in e.args:
            b = bounds(a)
            if b is None:
                return None
            lo, hi = lo + b[0], hi + b[1]
        return (lo, hi)
    if isinstance(e, sp.Max):
        parts = [bounds(a) for a in e.args]
        lows = [p[0] for p in parts if p is not None]
        if len(lows) < len(parts):  # an unbounded argument: only a floor is known
            return None
        return (max(lows), max(p[1] for p in parts))
    if not isinstance(e, sp.Function):
        return None
    fixed = _FIXED.get(e.func)
    rest = e.args[1:]
    if (e.func in _INCREASING or e.func in _DECREASING) and all(r.is_Number for r in rest):
        b = bounds(e.args[0])
        if b is not None:
            lo = _num(e.func(sp.Float(b[0]), *rest))
            hi = _num(e.func(sp.Float(b[1]), *rest))
            if lo is not None and hi is not None:
                return (min(lo, hi), max(lo, hi))
    if isinstance(e, Sat) and all(r.is_Number for r in rest):
        return (float(rest[0]), float(rest[1]))
    return fixed


def _within(b: tuple[float, float] | None, lo: float, hi: float) -> bool:
    return b is not None and lo <= b[0] and b[1] <= hi


# -- rules ----------------------------------------------------------------------

#: Functions that keep the sign of their first argument: sign(f(x, ...)) = sign(x).
_SIGN_KEEPING = (sp.tanh, sp.atan, SymLog, SymPow, GAsin, sp.asin, sp.sign)


def _ternary_factor(e: sp.Expr, ctx: _Context) -> tuple[sp.Expr, sp.Expr] | None:
    """``e = c t`` with ``t`` in {-1, 0, 1} (a sign or a relay) and ``c`` constant."""
    if isinstance(e, (sp.sign, Relay)):
        return sp.S.One, e
    if e.is_Mul:
        ts = [f for f in e.args if isinstance(f, (sp.sign, Relay))]
        if len(ts) == 1:
            c = e / ts[0]
            if ctx.constant(c):
                return c, ts[0]
    return None


def _odd(e: sp.Function) -> bool:
    if isinstance(e, Sat):
        return bool((e.args[1] + e.args[2]).is_zero)
    return isinstance(e, (sp.tanh, sp.atan, sp.sin, sp.sign, GTan, GAsin, sp.asin, SymLog,
                          SymPow, DeadZone, sp.tan))


def _odd_of_ternary(e: sp.Function, ctx: _Context) -> sp.Expr:
    """``f(c t, ...) = f(c, ...) t`` for an odd f and t in {-1, 0, 1}."""
    if not _odd(e) or not all(ctx.constant(r) for r in e.args[1:]):
        return e
    ct = _ternary_factor(e.args[0], ctx)
    if ct is None:
        return e
    c, t = ct
    return e.func(c, *e.args[1:]) * t


def _rule_sign(e: sp.Expr, ctx: _Context) -> sp.Expr:
    arg = e.args[0]
    if isinstance(arg, _SIGN_KEEPING) and all(ctx.constant(r) for r in arg.args[1:]):
        if not isinstance(arg, SymLog) or arg.args[1].is_positive:
            return sp.sign(arg.args[0])
    if isinstance(arg, Sat) and (arg.args[1] + arg.args[2]).is_zero and arg.args[2].is_positive:
        return sp.sign(arg.args[0])
    if isinstance(arg, Relay):
        return arg
    return e


def _rule_sat(e: sp.Expr, ctx: _Context) -> sp.Expr:
    y, lo, hi = e.args
    if lo.is_Number and hi.is_Number:
        if _within(bounds(y), float(lo), float(hi)):
            return y
        if isinstance(y, Sat) and y.args[1].is_Number and y.args[2].is_Number:
            nlo, nhi = max(lo, y.args[1]), min(hi, y.args[2])
            if nlo <= nhi:
                return Sat(y.args[0], nlo, nhi)
    return _odd_of_ternary(e, ctx)


def _rule_gtan(e: sp.Expr, ctx: _Context) -> sp.Expr:
    y = e.args[0]
    edge = math.atan(TAN_LIMIT)
    if _within(bounds(y), -edge, edge):
        return sp.tan(y)
    if isinstance(y, sp.atan):
        return Sat(y.args[0], -sp.Float(TAN_LIMIT), sp.Float(TAN_LIMIT))
    return _odd_of_ternary(e, ctx)


def _rule_guarded_arc(plain: Callable[[sp.Expr], sp.Expr]) -> Callable:
    def rule(e: sp.Expr, ctx: _Context) -> sp.Expr:
        if _within(bounds(e.args[0]), -1.0, 1.0):
            return plain(e.args[0])
        return _odd_of_ternary(e, ctx) if isinstance(e, GAsin) else e

    return rule


def _rule_sympow(e: sp.Expr, ctx: _Context) -> sp.Expr:
    y, a = e.args
    if a.is_Number and float(a) == 1.0:
        return Sat(y, -sp.Float(POW_INPUT_LIMIT), sp.Float(POW_INPUT_LIMIT))
    b = bounds(y)
    if isinstance(y, SymPow) and b is not None and a.is_Number and y.args[1].is_Number:
        inner = bounds(y.args[0])
        if inner is not None and max(abs(inner[0]), abs(inner[1])) <= 1.0:
            return SymPow(y.args[0], a * y.args[1])
    return _odd_of_ternary(e, ctx)


def _rule_dead_zone(e: sp.Expr, ctx: _Context) -> sp.Expr:
    y, a = e.args
    if a.is_Number and _within(bounds(y), -float(a), float(a)):
        return sp.S.Zero
    return _odd_of_ternary(e, ctx)


def _rule_max(e: sp.Expr, ctx: _Context) -> sp.Expr:
    if len(e.args) != 2:
        return e
    nums = [a for a in e.args if a.is_Number]
    if len(nums) != 1:
        return e
    lo = float(nums[0])
    y = next(a for a in e.args if not a.is_Number)
    b = bounds(y)
    if b is not None and b[0] >= lo:
        return y
    if b is not None and b[1] <= lo:
        return nums[0]
    return e


def _rule_odd(e: sp.Expr, ctx: _Context) -> sp.Expr:
    return _odd_of_ternary(e, ctx)


def _rule_relay(e: sp.Expr, ctx: _Context) -> sp.Expr:
    y, a = e.args
    if y.is_Mul:
        c, rest = y.as_independent(*ctx.signals, LTI, Delay, Relay, as_Add=False)
        if c != 1 and ctx.constant(c):
            sg = sp.sign(c)
            if sg in (1, -1):
                return sg * Relay(rest, a / (sg * c))
    return e


def _rule_mul(e: sp.Expr, ctx: _Context) -> sp.Expr:
    dyn = [f for f in e.args if isinstance(f, (LTI, Delay))]
    if len(dyn) == 1:
        c = e / dyn[0]
        if ctx.constant(c):
            op = dyn[0]
            if isinstance(op, LTI):
                return LTI(op.args[0], _tf(c * op.args[1], ctx))
            return Delay(c * op.args[0], op.args[1])
    out = sp.expand_mul(e, deep=False)
    return out


def _rule_lti(e: sp.Expr, ctx: _Context) -> sp.Expr:
    y, G = e.args
    if isinstance(y, LTI):
        return LTI(y.args[0], _tf(y.args[1] * G, ctx))
    if isinstance(y, Delay):
        return Delay(LTI(y.args[0], G), y.args[1])
    if y.is_Mul:
        c, rest = y.as_independent(*ctx.signals, LTI, Delay, Relay, as_Add=False)
        if c != 1 and ctx.constant(c):
            return LTI(rest, _tf(c * G, ctx))
    new_G = _tf(G, ctx)
    return LTI(y, new_G) if new_G != G else e


def _rule_delay(e: sp.Expr, ctx: _Context) -> sp.Expr:
    y, T = e.args
    if isinstance(y, Delay):
        return Delay(y.args[0], y.args[1] + T)
    return e


def _delay_outwards(e: sp.Function, ctx: _Context) -> sp.Expr:
    """``f(Delay(y, T), c...) = Delay(f(y, c...), T)`` when ``f(0, c...) = 0``."""
    if not e.args or not isinstance(e.args[0], Delay):
        return e
    rest = e.args[1:]
    if not all(ctx.constant(r) for r in rest):
        return e
    if isinstance(e, Relay) or e.func(sp.S.Zero, *rest).is_zero:
        d = e.args[0]
        return Delay(e.func(d.args[0], *rest), d.args[1])
    return e


_RULES: tuple[tuple[type, Callable[[sp.Expr, _Context], sp.Expr]], ...] = (
    (LTI, _rule_lti),
    (Delay, _rule_delay),
    (Relay, _rule_relay),
    (sp.sign, _rule_sign),
    (Sat, _rule_sat),
    (GTan, _rule_gtan),
    (GAsin, _rule_guarded_arc(sp.asin)),
    (GAcos, _rule_guarded_arc(sp.acos)),
    (SymPow, _rule_sympow),
    (DeadZone, _rule_dead_zone),
    (sp.Max, _rule_max),
    ((sp.tanh, sp.atan, sp.sin, SymLog, sp.tan, sp.asin), _rule_odd),
    (sp.Mul, _rule_mul),
)


# -- transfer functions ---------------------------------------------------------


def _tf(G: sp.Expr, ctx: _Context) -> sp.Expr:  # noqa: N803
    if ctx.numeric:
        num, den = _numeric_coefficients(G)
        try:
            nf = [float(c) for c in num]
            df = [float(c) for c in den]
        except TypeError:  # a symbol left: treat as named
            return sp.cancel(G, s)
        return rational(*_float_coeffs(*minreal(nf, df, tol=ctx.pz_tol)))
    # Named forms: each factor cancelled once; sympy's Mul keeps products
    # factored and removes identical factors of numerator and denominator.
    return sp.Mul(*(sp.cancel(f, s) for f in sp.Mul.make_args(G)))


def _numeric_coefficients(G: sp.Expr) -> tuple[list[sp.Expr], list[sp.Expr]]:  # noqa: N803
    num, den = sp.fraction(sp.together(G))
    return sp.Poly(num, s).all_coeffs(), sp.Poly(den, s).all_coeffs()


def _float_coeffs(num: np.ndarray, den: np.ndarray) -> tuple[list[sp.Expr], list[sp.Expr]]:
    def conv(c: float) -> sp.Expr:
        return sp.S.One if c == 1.0 else sp.Float(float(c), 17)

    return [conv(c) for c in np.atleast_1d(num)], [conv(c) for c in np.atleast_1d(den)]


def minreal(
    num: list[float] | np.ndarray, den: list[float] | np.ndarray, *, tol: float = 1e-6
) -> tuple[np.ndarray, np.ndarray]:
    """Cancel coinciding poles and zeros of ``num(s)/den(s)``; scale ``den`` monic.

    Parameters
    ----------
    num, den : array_like
        Coefficients in descending powers of s.
    tol : float, default 1e-6
        A zero and a pole cancel when ``|z - p| <= tol * max(|z|, |p|)``
        (exactly equal ones always cancel).

    Returns
    -------
    num, den : numpy.ndarray
        The reduced coefficients, ``den[0] == 1``.
    """
    num = np.trim_zeros(np.asarray(num, dtype=float), "f")
    den = np.trim_zeros(np.asarray(den, dtype=float), "f")
    if num.size == 0:
        return np.zeros(1), np.ones(1)
    zeros, poles = list(np.roots(num)), list(np.roots(den))
    kept_z = []
    for z in zeros:
        match = None
        for k, p in enumerate(poles):
            if abs(z - p) <= tol * max(abs(z), abs(p)) or z == p:
                match = k
                break
        if match is None:
            kept_z.append(z)
        else:
            poles.pop(match)
    if len(kept_z) == len(zeros):
        return num / den[0], den / den[0]
    gain = num[0] / den[0]
    return (gain * np.atleast_1d(np.real(np.poly(kept_z))),
            np.atleast_1d(np.real(np.poly(poles))))
