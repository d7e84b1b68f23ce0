"""python-control forms of the model: transfer functions per stage, a system per row.

The discrete transfer functions hold exactly the coefficients the simulator
filters with (``Stage.b``, ``Stage.a``, made once by :mod:`edm_sym.core.discrete`).
Those are in ascending powers of z^-1; multiplying numerator and denominator by
``z^(L-1)``, ``L = max(len(b), len(a))``, turns both, padded with zeros to
length L, into coefficient lists in descending powers of z, which is what
``control.tf(num, den, dt)`` takes.

Each row is a discrete :class:`control.NonlinearIOSystem` (``dt = Ts``) whose
state concatenates every stage's state, left to right, and whose update is
each stage's realisation (:meth:`~edm_sym.core.elements.realisation.Realisation.update`):
the direct form II transposed filter states of a linear stage (the structure
of :func:`scipy.signal.lfilter`), the buffer of a delay (newest first), the
held output of a relay; static maps have none. Simulated with
:func:`control.input_output_response` it reproduces the reference simulator.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import control as ct
import numpy as np
import sympy as sp

from edm_sym.core.elements import Element
from edm_sym.core.elements.realisation import DelayLine, LinearFilter, Realisation
from edm_sym.engines.symbolic.operators import rational, s


class StageView(Protocol):
    """What these forms read of a stage (:class:`~edm_sym.engines.symbolic.model.Stage`).

    Read through this view, so that this module does not import ``model.py``,
    whose :meth:`~edm_sym.engines.symbolic.model.SymbolicModel.to_control` imports it.
    """

    col: int
    element: type[Element]
    realisation: Realisation

    def numeric_tf(self) -> tuple[Any, Any]: ...


class RowView(Protocol):
    """What these forms read of a row (:class:`~edm_sym.engines.symbolic.model.RowModel`)."""

    index: int
    input: str
    stages: Sequence[StageView]


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


def stage_parts(row: RowView, ts: float) -> tuple[LinearPart, ...]:
    """The linear stages (filters and delays) of ``row`` as :class:`LinearPart` objects.

    ``ts`` is the sample time [s]; static maps and relays have no part.
    """
    parts = []
    for st in row.stages:
        name = f"row_{row.index + 1}_{st.element.name}_{st.col}"
        part = _PARTS.get(type(st.realisation))
        if part is not None:
            parts.append(part(st, name, ts))
    return tuple(parts)


def _filter_part(st: StageView, name: str, ts: float) -> LinearPart:
    r = st.realisation
    return LinearPart(st.col, st.element.name, to_tf(rational(*st.numeric_tf()), name),
                      discrete_tf(r.b, r.a, ts, f"{name}_d"), r.method)


def _delay_part(st: StageView, name: str, ts: float) -> LinearPart:
    n = st.realisation.samples
    return LinearPart(st.col, st.element.name, None,
                      ct.tf([1.0], [1.0] + [0.0] * n, dt=ts, name=f"{name}_d"), "delay")


#: The python-control form of each linear realisation type (static maps and relays have none).
_PARTS = {LinearFilter: _filter_part, DelayLine: _delay_part}


# -- the row as one discrete nonlinear system -----------------------------------


def state_labels(row: RowView) -> list[str]:
    """Names of the row system's states: ``c<col>_z<i>``, ``c<col>_d<i>``, ``c<col>_relay``.

    Parameters
    ----------
    row : RowModel or RowView

    Returns
    -------
    list of str
    """
    return [label for st in row.stages for label in st.realisation.state_labels(f"c{st.col}")]


def row_system(row: RowView, ts: float) -> ct.NonlinearIOSystem:
    """The row as a discrete python-control system (``dt = ts``), starting from rest.

    Parameters
    ----------
    row : RowModel or RowView
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
        chain.append((k, st.realisation.update))
        k += st.realisation.state_size
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


def compensator_system(model: Any, *, output: str = "tau_cmp",
                       name: str | None = None) -> ct.NonlinearIOSystem:
    """The whole compensator as one discrete python-control system (``dt = Ts``), from rest.

    Parameters
    ----------
    model : SymbolicModel
        From :func:`~edm_sym.engines.symbolic.model.build_model` or
        :func:`~edm_sym.engines.symbolic.decode` (the stages suffice).
    output : str, default "tau_cmp"
        The output's name.
    name : str, optional
        The system's name (default ``"edm_compensator"``).

    Returns
    -------
    control.NonlinearIOSystem
        Inputs: every input of the model, in its order (named as the
        columns, so :func:`control.interconnect` connects them by name; an
        input no row reads is an input all the same, and its value is
        ignored). One output, the sum of the rows. States: every row's
        stages' states, ``r<row>_c<col>_z<i>`` ... (see :func:`state_labels`),
        zero at the start as in the reference simulator. Updates and output
        run the realisations the simulator runs, so
        :func:`control.input_output_response` gives its numbers.
    """
    rows = []
    labels: list[str] = []
    k = 0
    for row in model.rows:
        chain = []
        for st in row.stages:
            chain.append((k, st.realisation.update))
            k += st.realisation.state_size
        rows.append((model.inputs.index(row.input), tuple(chain)))
        labels += [f"r{row.index + 1}_{label}" for label in state_labels(row)]
    nstates = k

    def run(x: Any, u: Any) -> tuple[float, np.ndarray]:
        x = np.asarray(x, dtype=float).reshape(nstates)
        u = np.asarray(u, dtype=float).reshape(-1)
        nxt = x.copy()
        total = 0.0
        for col, chain in rows:
            v = float(u[col])
            for offset, step in chain:
                v = step(v, x, nxt, offset)
            total += v
        return total, nxt

    def updfcn(t: float, x: Any, u: Any, params: Any) -> np.ndarray:
        return run(x, u)[1]

    def outfcn(t: float, x: Any, u: Any, params: Any) -> np.ndarray:
        return np.array([run(x, u)[0]])

    return ct.nlsys(updfcn, outfcn, inputs=list(model.inputs), outputs=[output],
                    states=labels, dt=model.sample_time, name=name or "edm_compensator")
