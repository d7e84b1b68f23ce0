"""The reference simulator: the numeric truth every export is checked against.

Each row is simulated over the whole log at once (vectorised over time, one
numpy/scipy call per element); the compensation torque is the sum of the rows.
:func:`simulate_rows` takes any number of rows, so the genetic algorithm can
evaluate many candidate rows in one call and cache them by their genes.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy import signal

from edm_sym.data import DataLog
from edm_sym.elements import LinearElement, StaticElement
from edm_sym.elements.ops import NUMPY
from edm_sym.matrix import Compensator, Row


@dataclass(frozen=True)
class Simulation:
    """Per-row outputs and their sum.

    Attributes
    ----------
    rows : numpy.ndarray
        Shape (m, N): the output of each row.
    total : numpy.ndarray
        Shape (N,): the compensation torque tau_cmp, the sum of the rows.
    """

    rows: np.ndarray
    total: np.ndarray

    def residual(self, target: np.ndarray) -> np.ndarray:
        """``target - tau_cmp``."""
        return np.asarray(target, dtype=float) - self.total


def simulate_row(comp: Compensator, row: Row, x: np.ndarray) -> np.ndarray:
    """Run one row over its input signal ``x`` (shape (N,)), left to right, from rest."""
    ts = comp.sample_time
    y = np.asarray(x, dtype=float)
    for gene in row.genes:
        y = gene.element.simulate(y, comp.value(gene), ts)
    return y


def simulate_rows(comp: Compensator, rows: Sequence[Row], inputs: np.ndarray) -> np.ndarray:
    """Simulate several rows (from any matrices sharing ``comp``'s ranges and Ts).

    Parameters
    ----------
    comp : Compensator
        Gives the sample time and parameter ranges.
    rows : sequence of Row
        Rows to simulate; ``row.input`` indexes the first axis of ``inputs``.
    inputs : numpy.ndarray
        Shape (n_inputs, N).

    Returns
    -------
    numpy.ndarray
        Shape (len(rows), N).
    """
    out = np.empty((len(rows), inputs.shape[-1]))
    for k, row in enumerate(rows):
        out[k] = simulate_row(comp, row, inputs[row.input])
    return out


def input_array(
    inputs: Sequence[str], data: DataLog | Mapping[str, np.ndarray]
) -> np.ndarray:
    """Stack the named input columns of a log (or a mapping) into (n_inputs, N)."""
    if isinstance(data, DataLog):
        return data.stack(inputs)
    return np.vstack([np.asarray(data[n], dtype=float) for n in inputs])


def simulate(result, data) -> Simulation:  # noqa: ANN001  (duck-typed on purpose)
    """Simulate a compensator over a data log.

    Parameters
    ----------
    result : EdmResult or Compensator
        The model.
    data : DataLog or mapping of str to array
        Must hold every input column of the model.

    Returns
    -------
    Simulation
        Per-row outputs ``rows`` (m, N) and their sum ``total`` (N,).
    """
    comp = result if isinstance(result, Compensator) else result.compensator
    x = input_array(comp.matrix.inputs, data)
    rows = simulate_rows(comp, comp.matrix.rows, x)
    return Simulation(rows, rows.sum(axis=0))


def plain_loop(comp: Compensator, data: DataLog | Mapping[str, np.ndarray]) -> np.ndarray:
    """The same computation as :func:`simulate`, one sample at a time in plain Python.

    This is the per-sample realisation a firmware loop would run; it serves
    as the baseline of the benchmarks and as an independent cross-check.
    Returns an (m, N) array of row outputs.
    """
    x = input_array(comp.matrix.inputs, data)
    ts = comp.sample_time
    steppers = [[g.element.stepper(comp.value(g), ts) for g in row.genes]
                for row in comp.matrix.rows]
    srcs = [row.input for row in comp.matrix.rows]
    cols = x.T.tolist()
    out = np.empty((len(steppers), x.shape[1]))
    for k, sample in enumerate(cols):
        for j, chain in enumerate(steppers):
            v = sample[srcs[j]]
            for st in chain:
                v = st(v)
            out[j, k] = v
    return out


def fitness(residual: np.ndarray, weights: np.ndarray | float = 1.0) -> float:
    """The paper's eq. 8: ``sqrt(mean(Lambda * residual**2))``."""
    r = np.asarray(residual, dtype=float)
    return float(np.sqrt(np.mean(np.asarray(weights) * r * r)))


# -- fast path for the genetic algorithm -------------------------------------
# The genetic algorithm simulates hundreds of thousands of rows whose filter
# parameters are new every time, so the cached scipy discretisation of
# :func:`edm_sym.discrete.discretize` (tf -> state space -> bilinear -> tf,
# 0.2 ms for a first-order and 8 ms for a second-order filter) would dominate.
# The functions below substitute s directly into the polynomials, which gives
# the same difference equations to rounding (relative 1e-12 or better; see
# tests/test_abstraction_fastsim.py). They only add to this module: the
# reference functions above are unchanged and remain the numeric truth.


def _poly_mul(p: list[float], q: list[float]) -> list[float]:
    out = [0.0] * (len(p) + len(q) - 1)
    for i, a in enumerate(p):
        for j, b in enumerate(q):
            out[i + j] += a * b
    return out


def _poly_pow(p: list[float], k: int) -> list[float]:
    out = [1.0]
    for _ in range(k):
        out = _poly_mul(out, p)
    return out


def _substitute(coeffs: list[float], order: int, num_w: list[float], den_w: list[float]
                ) -> list[float]:
    """``sum c_i s^d_i`` with s = num_w(w) / den_w(w), times den_w^order, in powers of w."""
    out = [0.0] * (order + 1)
    deg = len(coeffs) - 1
    for i, c in enumerate(coeffs):
        d = deg - i
        if c == 0.0:
            continue
        term = _poly_mul(_poly_pow(num_w, d), _poly_pow(den_w, order - d))
        for k, t in enumerate(term):
            out[k] += c * t
    return out


def fast_coefficients(cls: type, a: float | None, ts: float) -> tuple[np.ndarray, np.ndarray]:
    """Discrete coefficients of a linear element without scipy's state-space round trip.

    Parameters
    ----------
    cls : type of LinearElement
        The element class (its ``tf`` and ``method``).
    a : float or None
        The decoded parameter.
    ts : float
        Sample time [s].

    Returns
    -------
    b, a : numpy.ndarray
        In ascending powers of z^-1 with ``a[0] == 1``; equal to
        ``cls.coefficients(a, ts)`` up to rounding.
    """
    num, den = cls.tf(a)
    num = [float(c) for c in num]
    den = [float(c) for c in den]
    order = max(len(num), len(den)) - 1
    if cls.method == "bilinear":
        c = 2.0 / ts
        s_num, s_den = [c, -c], [1.0, 1.0]  # s = c (1 - w) / (1 + w)
    elif cls.method == "backward_diff":
        s_num, s_den = [1.0 / ts, -1.0 / ts], [1.0]  # s = (1 - w) / ts
    else:
        return cls.coefficients(a, ts)
    b = _substitute(num, order, s_num, s_den)
    d = _substitute(den, order, s_num, s_den)
    a0 = d[0]
    return np.array(b) / a0, np.array(d) / a0


def simulate_element_fast(cls: type, x: np.ndarray, a: float | None, ts: float) -> np.ndarray:
    """One element over a whole signal: :meth:`Element.simulate`, faster for the GA.

    Static elements skip the broadcasting multiply; linear elements use
    :func:`fast_coefficients` and a numpy FIR when the denominator is 1;
    delays and the relay use the reference code.

    Parameters
    ----------
    cls : type of Element
        The element class.
    x : numpy.ndarray
        Shape (N,) input signal.
    a : float or None
        The decoded parameter.
    ts : float
        Sample time [s].

    Returns
    -------
    numpy.ndarray
        Shape (N,) output, from rest.
    """
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        if issubclass(cls, StaticElement):
            y = cls.f(NUMPY, x, a)
            if not isinstance(y, np.ndarray) or y.shape != x.shape or y.dtype != np.float64:
                y = np.asarray(y, dtype=float) * np.ones_like(x)
            return y
        if issubclass(cls, LinearElement):
            b, den = fast_coefficients(cls, a, ts)
            if len(den) == 1 or not np.any(den[1:]):
                y = b[0] * x
                for k in range(1, len(b)):
                    if b[k] != 0.0:
                        y[k:] += b[k] * x[:-k]
                return y
            return signal.lfilter(b, den, x)
        return cls.simulate(x, a, ts)


def simulate_genes_fast(
    elements: Sequence[tuple[type, float | None]], x: np.ndarray, ts: float
) -> np.ndarray:
    """One row given as (element class, decoded parameter) pairs, with the fast path.

    Parameters
    ----------
    elements : sequence of (type of Element, float or None)
        The row's elements, left to right (see :meth:`Compensator.row_elements`).
    x : numpy.ndarray
        Shape (N,) selected input signal.
    ts : float
        Sample time [s].

    Returns
    -------
    numpy.ndarray
        Shape (N,) row output; equal to :func:`simulate_row` up to rounding.
    """
    y = np.asarray(x, dtype=float)
    for cls, a in elements:
        y = simulate_element_fast(cls, y, a, ts)
    return y
