"""How much each row contributes on a data log (the paper's Fig. 18 f-j).

The rows are simulated with the reference simulator; the RMS of each row's
output says how large it is, and the RMSE of ``target - (y_1 + ... + y_k)``
after adding the rows one by one says how much each one improves the fit.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from edm_sym.core.data import DataLog
from edm_sym.core.fitness import rms
from edm_sym.core.matrix import Compensator
from edm_sym.engines.simulate import input_array, simulate_rows


@dataclass(frozen=True)
class Contributions:
    """Row-by-row contributions on one data log.

    Attributes
    ----------
    rms : tuple of float
        RMS of each row's output [N m], in row order.
    rmse_cumulative : tuple of float
        ``rmse_cumulative[k]``: RMSE of ``target - sum of rows 0..k`` [N m].
    rmse_none : float
        RMS of the target itself (the RMSE with no row).
    improvement : tuple of float
        The drop of the RMSE as each row is added (positive = better).
    """

    rms: tuple[float, ...]
    rmse_cumulative: tuple[float, ...]
    rmse_none: float

    @property
    def improvement(self) -> tuple[float, ...]:
        """The drop of the RMSE as each row is added (positive: the row helps)."""
        before = (self.rmse_none,) + self.rmse_cumulative[:-1]
        return tuple(b - a for b, a in zip(before, self.rmse_cumulative, strict=True))

    def table(self) -> str:
        """A plain-text table, one line per row."""
        lines = [f"{'row':>4} {'rms [N m]':>12} {'rmse [N m]':>12} {'drop':>12}",
                 f"{'-':>4} {'':>12} {self.rmse_none:12.6g} {'':>12}"]
        for k, (r, e, d) in enumerate(zip(self.rms, self.rmse_cumulative, self.improvement,
                                              strict=True)):
            lines.append(f"{k + 1:>4} {r:12.6g} {e:12.6g} {d:12.6g}")
        return "\n".join(lines)




def contributions(
    model_or_result: Any, data: DataLog | Mapping[str, np.ndarray], target: str | np.ndarray
) -> Contributions:
    """RMS of each row and the RMSE after adding the rows one by one.

    Parameters
    ----------
    model_or_result : SymbolicModel, EdmResult or Compensator
        The compensator (a decoded model is simulated from its compensator).
    data : DataLog or mapping of str to array
        Holds every input column (and the target column when ``target`` is a name).
    target : str or numpy.ndarray
        The target column's name, or the target signal itself.

    Returns
    -------
    Contributions
    """
    comp = model_or_result
    if not isinstance(comp, Compensator):
        comp = comp.compensator
    x = input_array(comp.matrix.inputs, data)
    if isinstance(target, str):
        y = data.column(target, role="target") if isinstance(data, DataLog) else data[target]
    else:
        y = target
    y = np.asarray(y, dtype=float)
    if y.shape != (x.shape[1],):
        raise ValueError(f"target: expected {x.shape[1]} samples like the inputs, "
                         f"found shape {y.shape}")
    rows = simulate_rows(comp, comp.matrix.rows, x)
    cum = np.cumsum(rows, axis=0)
    return Contributions(tuple(rms(r) for r in rows), tuple(rms(y - c) for c in cum), rms(y))
