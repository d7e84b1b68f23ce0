"""The reference simulator: the numeric truth every export is checked against.

Each row is simulated over the whole log at once (vectorised over time, one
numpy/scipy call per element: the :meth:`run` of the element's realisation,
:mod:`edm_sym.core.elements.realisation`); the compensation torque is the sum of
the rows. The genetic algorithm runs the same realisations.
:func:`simulate_rows` takes any number of rows, so the genetic algorithm can
evaluate many candidate rows in one call and cache them by their genes.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from edm_sym.core.budget import check, simulation_estimate
from edm_sym.core.data import TIME_RTOL, DataLog
from edm_sym.core.errors import DataFormatError, ResultFormatError
from edm_sym.core.fitness import fitness
from edm_sym.core.matrix import Compensator, Row

__all__ = [
    "Simulation", "checked_inputs", "fitness", "input_array", "plain_loop", "segments", "simulate",
    "simulate_row", "simulate_rows",
]


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
        """``target - tau_cmp``.

        Raises
        ------
        DataFormatError
            When ``target`` is not one real number per sample.
        """
        y = np.asarray(target, dtype=float) if target is not None else np.empty(0)
        if y.shape != self.total.shape:
            raise DataFormatError("target", f"expected {self.total.shape[0]} samples like the "
                                  f"simulation, found shape {y.shape}")
        return y - self.total


def simulate_row(comp: Compensator, row: Row, x: np.ndarray, *,
                 starts: Sequence[int] = ()) -> np.ndarray:
    """Run one row over its input signal ``x`` (shape (N,)), left to right, from rest.

    ``starts``: where further logs begin in ``x`` (several logs side by side,
    :func:`segments`): each is simulated from rest on its own, never joined to
    the one before.
    """
    if starts:
        return np.concatenate([simulate_row(comp, row, x[a:b]) for a, b in segments(len(x), starts)])
    ts = comp.sample_time
    y = np.asarray(x, dtype=float)
    for gene in row.genes:
        y = gene.element.realise(comp.value(gene), ts).run(y)
    return y


def segments(n: int, starts: Sequence[int]) -> list[tuple[int, int]]:
    """The ``(start, stop)`` of each log of ``n`` samples laid end to end, the later ones
    beginning at ``starts``."""
    edges = [0, *starts, n]
    return [(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:], strict=True)]


def simulate_rows(comp: Compensator, rows: Sequence[Row], inputs: np.ndarray, *,
                  starts: Sequence[int] = ()) -> np.ndarray:
    """Simulate several rows (from any matrices sharing ``comp``'s ranges and Ts).

    Parameters
    ----------
    comp : Compensator
        Gives the sample time and parameter ranges.
    rows : sequence of Row
        Rows to simulate; ``row.input`` indexes the first axis of ``inputs``.
    inputs : numpy.ndarray
        Shape (n_inputs, N).
    starts : sequence of int
        Where further logs begin (:func:`simulate_row`).

    Returns
    -------
    numpy.ndarray
        Shape (len(rows), N).
    """
    out = np.empty((len(rows), inputs.shape[-1]))
    for k, row in enumerate(rows):
        out[k] = simulate_row(comp, row, inputs[row.input], starts=starts)
    return out


def input_array(
    inputs: Sequence[str], data: DataLog | Mapping[str, np.ndarray]
) -> np.ndarray:
    """Stack the named input columns of a log (or a mapping) into (n_inputs, N)."""
    if isinstance(data, DataLog):
        return data.stack(inputs)
    return np.vstack([np.asarray(data[n], dtype=float) for n in inputs])


def checked_inputs(comp: Compensator, data: DataLog | Mapping[str, np.ndarray]) -> np.ndarray:
    """The model's input columns of ``data`` as (n_inputs, N), refusing what would mislead.

    Raises
    ------
    DataFormatError
        Naming the log and column (and row): a missing input, columns of other
        shapes or lengths, no sample, a value that is not finite (NaN would
        spread through every filter after it), or a log whose sample time is
        not the model's (within :data:`~edm_sym.core.data.TIME_RTOL`).
    """
    if not isinstance(data, DataLog | Mapping):
        raise DataFormatError("data", f"expected a DataLog or a mapping of column names to "
                              f"arrays, found {type(data).__name__}")
    source = getattr(data, "source", None) or "data"
    have = data.columns if isinstance(data, DataLog) else data
    if isinstance(data, DataLog) and abs(data.ts - comp.sample_time) > TIME_RTOL * comp.sample_time:
        raise DataFormatError(f"{source}: sample time",
                              f"expected {comp.sample_time:g} s as in the model (within "
                              f"{TIME_RTOL:g} relative), found {data.ts:g} s; resample the log "
                              "(edm_sym.core.data.match_sample_time)")
    cols = []
    for name in comp.matrix.inputs:
        if name not in have:
            raise DataFormatError(f"{source}: column {name!r}", f"expected the model's input "
                                  f"column, found only: {', '.join(map(str, have)) or 'none'}")
        col = np.asarray(have[name])
        if col.ndim != 1 or not np.issubdtype(col.dtype, np.number) or np.iscomplexobj(col):
            raise DataFormatError(f"{source}: column {name!r}", f"expected a 1-D array of real "
                                  f"numbers, found {col.dtype} of shape {col.shape}")
        if cols and len(col) != len(cols[0]):
            raise DataFormatError(f"{source}: column {name!r}", f"expected {len(cols[0])} samples "
                                  f"like column {comp.matrix.inputs[0]!r}, found {len(col)}")
        bad = np.flatnonzero(~np.isfinite(col))
        if bad.size:
            raise DataFormatError(f"{source}: row {bad[0] + 1}, column {name!r}",
                                  f"expected a finite number, found {col[bad[0]]}")
        cols.append(col.astype(float, copy=False))
    if not len(cols[0]):
        raise DataFormatError(source, "expected samples, found an empty log")
    return np.vstack(cols)


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

    Raises
    ------
    DataFormatError
        A missing input column, columns of other shapes or lengths, an empty
        log, a value that is not finite, or a DataLog whose sample time is not
        the model's (:func:`checked_inputs`).
    BudgetError
        When the rows' outputs would not fit in the memory available.
    """
    comp = result if isinstance(result, Compensator) else getattr(result, "compensator", None)
    if not isinstance(comp, Compensator):
        raise ResultFormatError("result", f"expected an EdmResult or a Compensator, found "
                                f"{type(result).__name__}")
    x = checked_inputs(comp, data)
    check(simulation_estimate(n_samples=x.shape[1], n_rows=len(comp.matrix.rows),
                              n_inputs=x.shape[0]),
          getattr(data, "source", None) or "data", "use a shorter log or a result with fewer rows")
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
