"""python-control forms of the model: transfer functions per stage, a system per row.

The discrete transfer functions hold exactly the coefficients the simulator
filters with (``Stage.b``, ``Stage.a``, made once by :mod:`edm_sym.discrete`).
Those are in ascending powers of z^-1; multiplying numerator and denominator by
``z^(L-1)``, ``L = max(len(b), len(a))``, turns both, padded with zeros to
length L, into coefficient lists in descending powers of z, which is what
``control.tf(num, den, dt)`` takes.

Each row is a discrete :class:`control.NonlinearIOSystem` (``dt = Ts``) whose
state concatenates every stage's state, left to right: the direct form II
transposed filter states of a linear stage (the structure of
:func:`scipy.signal.lfilter`), the buffer of a delay (newest first), the held
output of a relay. Static stages are the model's own expressions, lambdified.
Simulated with :func:`control.input_output_response` it reproduces the
reference simulator.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import control as ct
import numpy as np
import sympy as sp

from edm_sym.symbolic.functions import NUMPY_FUNCTIONS
from edm_sym.symbolic.model import RowModel, Stage, X
from edm_sym.symbolic.operators import rational, s


@dataclass(frozen=True)
class LinearPart:
    """A linear stage (filter or delay) of a row as python-control transfer functions.

    Attributes
    ----------
    col : int
        The stage's column.
    element : str
        The element name.
    continuous : control.TransferFunction or None
        ``G(s)`` with the parameter value; None for a delay (exp(-sT) is not rational).
    discrete : control.TransferFunction
        ``H(z)`` with ``dt = Ts``: the simulator's coefficients (a delay is z^-N).
    method : str
        The discretisation (``"bilinear"``, ``"backward_diff"`` or ``"delay"``).
    """

    col: int
    element: str
    continuous: ct.TransferFunction | None
    discrete: ct.TransferFunction
    method: str


def z_polynomials(b: Sequence[float], a: Sequence[float]) -> tuple[list[float], list[float]]:
    """Coefficients in ascending powers of z^-1 -> equal-length lists in descending powers of z.

    Parameters
    ----------
    b, a : sequence of float
        Numerator and denominator in ascending powers of z^-1.

    Returns
    -------
    num, den : list of float
        Both of length ``max(len(b), len(a))``, descending powers of z.
    """
    n = max(len(b), len(a))
    return ([float(v) for v in b] + [0.0] * (n - len(b)),
            [float(v) for v in a] + [0.0] * (n - len(a)))


def discrete_tf(b: Sequence[float], a: Sequence[float], ts: float,
                name: str | None = None) -> ct.TransferFunction:
    """``H(z)`` from coefficients in ascending powers of z^-1 (see :func:`z_polynomials`).

    Parameters
    ----------
    b, a : sequence of float
    ts : float
        The sample time [s].
    name : str, optional
        The system's name.

    Returns
    -------
    control.TransferFunction
    """
    num, den = z_polynomials(b, a)
    return ct.tf(num, den, dt=ts, name=name)


def to_tf(G: sp.Expr, name: str | None = None) -> ct.TransferFunction:  # noqa: N803
    """A continuous python-control transfer function from a numeric sympy ``G(s)``.

    Parameters
    ----------
    G : sympy.Expr
        Rational in :data:`s`, every other symbol substituted.
    name : str, optional
        The system's name.

    Returns
    -------
    control.TransferFunction
    """
    num, den = sp.fraction(sp.together(sp.sympify(G)))
    try:
        n = [float(c) for c in sp.Poly(num, s).all_coeffs()]
        d = [float(c) for c in sp.Poly(den, s).all_coeffs()]
    except TypeError as exc:
        raise ValueError(f"G(s) = {G}: expected numbers only besides s ({exc})") from None
    return ct.tf(n, d, name=name)


def stage_parts(row: RowModel, ts: float) -> tuple[LinearPart, ...]:
    """The linear stages (filters and delays) of a row as :class:`LinearPart` objects.

    Parameters
    ----------
    row : RowModel
    ts : float
        The sample time [s].

    Returns
    -------
    tuple of LinearPart
    """
    parts = []
    for st in row.stages:
        name = f"row_{row.index + 1}_{st.element.name}_{st.col}"
        if st.kind == "linear":
            num, den = st.tf
            if st.param is not None:
                sub = {st.param.symbol: sp.Float(st.param.value, 17)}
                num = [sp.sympify(c).xreplace(sub) for c in num]
                den = [sp.sympify(c).xreplace(sub) for c in den]
            parts.append(LinearPart(st.col, st.element.name, to_tf(rational(num, den), name),
                                    discrete_tf(st.b, st.a, ts, f"{name}_d"), st.method or ""))
        elif st.kind == "delay":
            n = st.delay
            parts.append(LinearPart(st.col, st.element.name, None,
                                    ct.tf([1.0], [1.0] + [0.0] * n, dt=ts, name=f"{name}_d"),
                                    "delay"))
    return tuple(parts)


# -- the row as one discrete nonlinear system -----------------------------------



def _static_step(st: Stage) -> tuple[int, Callable]:
    f = sp.lambdify(X, st.numeric_expr(), modules=[NUMPY_FUNCTIONS, "numpy"])

    def step(v: float, x: np.ndarray, nxt: np.ndarray, k: int) -> float:
        return float(f(v))

    return 0, step


def _linear_step(st: Stage) -> tuple[int, Callable]:
    b, a = z_polynomials(st.b, st.a)
    n = len(b) - 1

    def step(v: float, x: np.ndarray, nxt: np.ndarray, k: int) -> float:
        # Direct form II transposed, as scipy.signal.lfilter (a[0] == 1).
        y = b[0] * v + (x[k] if n else 0.0)
        for i in range(n - 1):
            nxt[k + i] = b[i + 1] * v + x[k + i + 1] - a[i + 1] * y
        if n:
            nxt[k + n - 1] = b[n] * v - a[n] * y
        return y

    return n, step


def _delay_step(st: Stage) -> tuple[int, Callable]:
    n = st.delay

    def step(v: float, x: np.ndarray, nxt: np.ndarray, k: int) -> float:
        if n == 0:
            return v
        y = x[k + n - 1]
        nxt[k + 1:k + n] = x[k:k + n - 1]
        nxt[k] = v
        return float(y)

    return n, step


def _relay_step(st: Stage) -> tuple[int, Callable]:
    thr = float(st.threshold)

    def step(v: float, x: np.ndarray, nxt: np.ndarray, k: int) -> float:
        y = 1.0 if v >= thr else (-1.0 if v <= -thr else float(x[k]))
        nxt[k] = y
        return y

    return 1, step


_STEPS = {"static": _static_step, "linear": _linear_step, "delay": _delay_step,
          "relay": _relay_step}


def state_labels(row: RowModel) -> list[str]:
    """Names of the row system's states: ``c<col>_z<i>``, ``c<col>_d<i>``, ``c<col>_relay``.

    Parameters
    ----------
    row : RowModel

    Returns
    -------
    list of str
    """
    out: list[str] = []
    for st in row.stages:
        if st.kind == "linear":
            out += [f"c{st.col}_z{i}" for i in range(max(len(st.b), len(st.a)) - 1)]
        elif st.kind == "delay":
            out += [f"c{st.col}_d{i}" for i in range(st.delay)]
        elif st.kind == "relay":
            out.append(f"c{st.col}_relay")
    return out


def row_system(row: RowModel, ts: float) -> ct.NonlinearIOSystem:
    """The row as a discrete python-control system (``dt = ts``), starting from rest.

    Parameters
    ----------
    row : RowModel
    ts : float
        The sample time [s].

    Returns
    -------
    control.NonlinearIOSystem
        One input (the row's input name), one output ``y_<row number>``, the
        stages' states concatenated (see :func:`state_labels`); the initial
        state is zero, as in the simulator.
    """
    chain = []
    k = 0
    for st in row.stages:
        size, step = _STEPS[st.kind](st)
        chain.append((k, step))
        k += size
    nstates = k

    def run(x: Any, u: Any) -> tuple[float, np.ndarray]:
        x = np.asarray(x, dtype=float).reshape(nstates)
        nxt = x.copy()
        v = float(np.asarray(u, dtype=float).reshape(-1)[0])
        for offset, step in chain:
            v = step(v, x, nxt, offset)
        return v, nxt

    def updfcn(t: float, x: Any, u: Any, params: Any) -> np.ndarray:
        return run(x, u)[1]

    def outfcn(t: float, x: Any, u: Any, params: Any) -> np.ndarray:
        return np.array([run(x, u)[0]])

    return ct.nlsys(updfcn, outfcn, inputs=[row.input], outputs=[f"y_{row.index + 1}"],
                    states=state_labels(row), dt=ts, name=f"row_{row.index + 1}")


def simulate_system(sys: ct.NonlinearIOSystem, x: np.ndarray) -> np.ndarray:
    """Run a row system over an input signal with :func:`control.input_output_response`.

    Parameters
    ----------
    sys : control.NonlinearIOSystem
        A discrete row system (see :func:`row_system`).
    x : numpy.ndarray
        Shape (N,): the input, one value per sample.

    Returns
    -------
    numpy.ndarray
        Shape (N,): the row output.
    """
    x = np.asarray(x, dtype=float)
    t = np.arange(x.size) * sys.dt
    resp = ct.input_output_response(sys, t, x)
    return np.asarray(resp.outputs, dtype=float).reshape(-1)
