"""The C library's math functions over arrays, to the bit, on any processor.

The generated C calls the C library's ``sin``, ``atan``, ``tanh``, ``pow``
...; the generated Python module calls :mod:`math`, which calls the same
functions. numpy's float64 functions are its own vectorised code wherever the
processor has the instructions for it: on an AVX-512 machine (measured on an
AMD EPYC, numpy 2.3 and 2.4) ``tan``, ``arcsin``, ``arccos``, ``arctan``,
``log1p``, ``power``, ``expm1`` and ``tanh`` each differ from the C library
in the last bit on 0.1 % to 25 % of arguments, on another machine other
functions or none. One last bit is far below the exports' 1e-9, but a chain
amplifies it: ``asin`` or ``acos`` of a value next to 1, a sharp notch. There
the generated code differed from the simulator by 1.5e-8 N m, and a seed's
search took another path on another processor.

So the simulator's elements (:class:`~edm_sym.core.elements.ops.NumpyOps`)
and the GA's row kernel compute these functions with the C library's scalar
functions, sample by sample, in one of two ways that give the same bits:

* :func:`numpy.frompyfunc` over :mod:`math`'s functions: no compilation and
  no import beyond numpy, about 50 ns a sample (1 ms for 20 000 samples);
* once the row kernel is loaded (:mod:`edm_sym.engines.kernel`, with numba
  installed: ``edm_sym[fast]``), which calls :func:`use_compiled`: numpy
  ufuncs compiled by numba whose loops call the C library, at about its own
  speed (5-10 ns a sample). Each is made on its first call (its compiled
  code cached on disk: about 50 ms to load). Not where numba would use
  Intel's SVML instead (``icc_rt`` installed): that is not the C library.

Each function takes an array (or a number) and an optional ``out`` array,
as a numpy ufunc does, and follows C's rules where Python's :mod:`math`
raises (``sin(inf)`` is NaN). tests/test_elements.py checks both ways
against :mod:`math` on millions of arguments.
"""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np

__all__ = ["acos", "asin", "atan", "cos", "log1p", "pow", "sin", "tan", "tanh", "make_all", "use_compiled"]


# The scalar functions the ufuncs loop over (numba compiles them: module level, so
# its cache can find them).
def _sin(x: float) -> float:
    return math.sin(x)


def _cos(x: float) -> float:
    return math.cos(x)


def _tan(x: float) -> float:
    return math.tan(x)


def _asin(x: float) -> float:
    return math.asin(x)


def _acos(x: float) -> float:
    return math.acos(x)


def _atan(x: float) -> float:
    return math.atan(x)


def _tanh(x: float) -> float:
    return math.tanh(x)


def _log1p(x: float) -> float:
    return math.log1p(x)


def _pow(x: float, a: float) -> float:
    return math.pow(x, a)


_SCALAR = {"sin": _sin, "cos": _cos, "tan": _tan, "asin": _asin, "acos": _acos,
           "atan": _atan, "tanh": _tanh, "log1p": _log1p, "pow": _pow}


def _c_rules(name: str, fn: Any) -> Any:
    """``fn`` with C's answer where Python's :mod:`math` raises instead."""
    def call(*args: float) -> float:
        try:
            return fn(*args)
        except ValueError:  # a domain error: C returns NaN, or a pole's infinity
            if name == "log1p" and args[0] == -1.0:
                return -math.inf
            if name == "pow" and args[0] == 0.0 and args[1] < 0:
                odd = args[1] == int(args[1]) and int(args[1]) % 2
                return math.copysign(math.inf, args[0]) if odd else math.inf
            return math.nan
        except OverflowError:  # pow only: C returns +-inf
            x, a = args
            return -math.inf if x < 0 and a == int(a) and int(a) % 2 else math.inf

    return call


def _python_ufunc(name: str) -> Any:
    fn = _SCALAR[name]
    nargs = fn.__code__.co_argcount
    obj = np.frompyfunc(_c_rules(name, fn), nargs, 1)

    def ufunc(*args: Any, out: np.ndarray | None = None) -> Any:
        res = obj(*(np.asarray(a, dtype=float) for a in args))
        if out is None:
            return np.asarray(res, dtype=float) if isinstance(res, np.ndarray) else float(res)
        np.copyto(out, np.asarray(res, dtype=float))
        return out

    return ufunc


#: Whether the functions are numba's compiled ufuncs (:func:`use_compiled`).
_COMPILED = {"on": False}


def use_compiled() -> bool:
    """Compute with numba's compiled ufuncs from now on, where numba can (the same bits, faster).

    Returns whether it can: False without numba, or where numba would use Intel's SVML.
    """
    try:
        import numba
    except ImportError:  # pragma: no cover (depends on the installation)
        return False
    if getattr(numba.config, "USING_SVML", False):  # pragma: no cover
        return False
    _COMPILED["on"] = True
    return True


@functools.cache
def _compiled(name: str) -> Any:
    import numba

    sig = "float64(float64, float64)" if name == "pow" else "float64(float64)"
    return numba.vectorize([sig], nopython=True, cache=True)(_SCALAR[name])


@functools.cache
def _interpreted(name: str) -> Any:
    return _python_ufunc(name)


def _ufunc(name: str) -> Any:
    return _compiled(name) if _COMPILED["on"] else _interpreted(name)


def make_all() -> None:
    """Make every function now (before a fork, so the forked processes have them)."""
    for name in _SCALAR:
        _ufunc(name)


def sin(x: Any, out: np.ndarray | None = None) -> Any:
    """The C library's ``sin`` of each element."""
    return _ufunc("sin")(x, out=out)


def cos(x: Any, out: np.ndarray | None = None) -> Any:
    """The C library's ``cos`` of each element."""
    return _ufunc("cos")(x, out=out)


def tan(x: Any, out: np.ndarray | None = None) -> Any:
    """The C library's ``tan`` of each element."""
    return _ufunc("tan")(x, out=out)


def asin(x: Any, out: np.ndarray | None = None) -> Any:
    """The C library's ``asin`` of each element (NaN outside [-1, 1])."""
    return _ufunc("asin")(x, out=out)


def acos(x: Any, out: np.ndarray | None = None) -> Any:
    """The C library's ``acos`` of each element (NaN outside [-1, 1])."""
    return _ufunc("acos")(x, out=out)


def atan(x: Any, out: np.ndarray | None = None) -> Any:
    """The C library's ``atan`` of each element."""
    return _ufunc("atan")(x, out=out)


def tanh(x: Any, out: np.ndarray | None = None) -> Any:
    """The C library's ``tanh`` of each element."""
    return _ufunc("tanh")(x, out=out)


def log1p(x: Any, out: np.ndarray | None = None) -> Any:
    """The C library's ``log1p`` of each element."""
    return _ufunc("log1p")(x, out=out)


def pow(x: Any, a: Any, out: np.ndarray | None = None) -> Any:  # noqa: A001 (C's name)
    """The C library's ``pow(x, a)`` of each element (``a`` broadcast)."""
    return _ufunc("pow")(x, a, out=out)
