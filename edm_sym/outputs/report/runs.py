"""The compensator (and the LuGre baseline) run on the report's data logs.

A :class:`LogRun` holds everything the report shows about one log: the
target, each row's output and their sum from the reference simulator, the
residual's RMSE, the row contributions (paper, Fig. 18 f-j) and, when a LuGre
result is given, the LuGre model's torque on the same log (Table III).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from edm_sym.core.data import TIME_RTOL, DataLog, match_sample_time
from edm_sym.core.errors import DataFormatError
from edm_sym.core.fitness import rms
from edm_sym.engines.models import model_of
from edm_sym.engines.simulate import simulate
from edm_sym.engines.sources import load_data
from edm_sym.engines.symbolic.contributions import Contributions, contributions


@dataclass(frozen=True)
class LuGreRef:
    """A LuGre result for the comparison, with where it came from.

    Attributes
    ----------
    result : LuGreResult
    name : str
        The file name (no folder).
    sha256 : str
        The sha256 of the file.
    """

    result: Any
    name: str
    sha256: str


@dataclass(frozen=True)
class LogRun:
    """The compensator run on one data log.

    Attributes
    ----------
    label : str
        ``"abstraction"`` or ``"evaluation"``.
    name, sha256 : str
        The log file's name (no folder) and digest.
    ts : float
        Sample time [s].
    t, target, total : numpy.ndarray
        Time [s], the target and the compensation (the sum of the rows) in the axis's force
        unit (N m or N).
    rows : numpy.ndarray
        Shape (m, N): each row's output (N m or N).
    rmse : float
        RMSE of ``target - total`` (N m or N).
    contributions : Contributions
        Row RMS and cumulative RMSE.
    lugre, lugre_rmse : numpy.ndarray or None, float or None
        The LuGre model's torque on this log and its RMSE, when a LuGre result is given.
    inputs : numpy.ndarray or None
        Shape (n_inputs, N): the compensator's inputs on this log, in the result's order.
    observer_bandwidth : float or None
        The observer's bandwidth [rad/s] ``edm abstract`` was told (result.json
        ``provenance.observer_bandwidth``), else the log's scalar
        ``observer_bandwidth`` (docs/describe.md#honest-names).
    number, of : int
        The log's place among the report's logs of its kind (1-based) and their count.
    beyond : tuple of str
        Where a row reads an input beyond the range the abstraction logs had
        (:meth:`~edm_sym.engines.models.EdmModel.beyond_ranges`): one line per input.
    """

    label: str
    name: str
    sha256: str | None
    ts: float
    t: np.ndarray
    target: np.ndarray
    rows: np.ndarray
    total: np.ndarray
    rmse: float
    contributions: Contributions
    lugre: np.ndarray | None = None
    lugre_rmse: float | None = None
    inputs: np.ndarray | None = None
    observer_bandwidth: float | None = None
    number: int = 1
    of: int = 1
    beyond: tuple[str, ...] = ()

    @property
    def key(self) -> str:
        """The log's part of its figures' names: the kind, then its number after the first."""
        return self.label if self.number == 1 else f"{self.label}{self.number}"

    @property
    def residual(self) -> np.ndarray:
        """``target - total`` (N m or N)."""
        return self.target - self.total

    @property
    def duration(self) -> float:
        """Length of the log, ``N Ts`` [s]."""
        return len(self.t) * self.ts


def load_log(path: str | Path, result: Any, *, ts: float | None = None,
             lugre: LuGreRef | None = None) -> DataLog:
    """Read a data log holding the result's inputs and target (and the LuGre velocity).

    Parameters
    ----------
    path : path-like
    result : EdmResult
    ts : float, optional
        Sample time for logs without a ``t`` column.
    lugre : LuGreRef, optional

    Raises
    ------
    DataFormatError
        On a missing column or a sample time other than the result's.
    """
    need = [*result.inputs, result.target]
    if lugre is not None and lugre.result.velocity_name:
        need.append(lugre.result.velocity_name)
    # The time column and roles the result records for its abstraction log, where this one has them.
    data = load_data(path, ts=ts, require=need, default_ts=result.sample_time,
                     columns=result.column_roles())
    return match_sample_time(data, result.sample_time, model="the result")


def run_log(result: Any, data: DataLog, *, label: str, lugre: LuGreRef | None = None) -> LogRun:
    """Simulate the compensator (and the LuGre model) on ``data``.

    Parameters
    ----------
    result : EdmResult
    data : DataLog
        From :func:`load_log`.
    label : {"abstraction", "evaluation"}
    lugre : LuGreRef, optional

    Returns
    -------
    LogRun
    """
    if label not in ("abstraction", "evaluation"):
        raise ValueError(f"label: expected 'abstraction' or 'evaluation', found {label!r}")
    sim = simulate(result, data)
    target = np.asarray(data.column(result.target, role="target"), dtype=float)
    t = data.times
    lugre_tau = lugre_rmse = None
    if lugre is not None:
        model = model_of(lugre.result, lugre.name)
        if abs(model.sample_time - data.ts) > TIME_RTOL * data.ts:
            raise DataFormatError(f"{lugre.name}: sample_time",
                                  f"expected {data.ts:g} s as in {data.source} (within {TIME_RTOL:g} "
                                  f"relative), found {model.sample_time:g} s")
        for col in model.inputs:
            data.column(col)
        lugre_tau = model.run(data).torque
        lugre_rmse = rms(target - lugre_tau)
    contrib = contributions(result, data, target)
    return LogRun(label, data.source, data.sha256, float(data.ts), t, target, sim.rows,
                  sim.total, rms(target - sim.total), contrib, lugre_tau, lugre_rmse,
                  data.stack(result.compensator.matrix.inputs),
                  result.observer_bandwidth or data.scalars.get("observer_bandwidth"),
                  beyond=tuple(model_of(result).beyond_ranges(data)))


@dataclass(frozen=True)
class SteadyState:
    """The velocity rows' torque at constant velocities (the friction characteristic).

    Attributes
    ----------
    velocity : numpy.ndarray
        The constant velocities (rad/s or m/s).
    settle : float
        How long each velocity was held [s].
    rows : tuple of int
        The rows shown (0-based): those whose input is a velocity and whose
        output settles.
    torque : numpy.ndarray
        Shape (len(rows), len(velocity)): each row's settled output (N m or N).
    unsettled : tuple of int
        Velocity rows whose output keeps changing (an integral, say).
    lugre : numpy.ndarray or None
        The LuGre model's steady state (eq. 14), when given.
    """

    velocity: np.ndarray
    settle: float
    rows: tuple[int, ...]
    torque: np.ndarray
    unsettled: tuple[int, ...]
    lugre: np.ndarray | None = None


def steady_state(result: Any, roles: Any, v_max: float, *, lugre: LuGreRef | None = None,
                 settle: float = 5.0, points: int = 201) -> SteadyState | None:
    """Hold each velocity for ``settle`` seconds and read the velocity rows' outputs.

    Parameters
    ----------
    result : EdmResult
    roles : sequence of str or None
        The role of each row's input (``RowModel.role``).
    v_max : float
        The velocities span ``[-v_max, v_max]`` (rad/s or m/s).
    lugre : LuGreRef, optional
    settle : float
        Seconds each velocity is held; a row still changing by more than
        0.1 % of its level over the last tenth of that is "unsettled".
    points : int
        Number of velocities (odd, so 0 is one of them).

    Returns
    -------
    SteadyState or None
        None when no row has a velocity input.
    """
    from edm_sym.engines.simulate import simulate_row

    comp = result.compensator
    idx = [j for j, role in enumerate(roles) if role == "velocity"]
    if not idx:
        return None
    v = np.linspace(-v_max, v_max, points)
    n = max(10, round(settle / comp.sample_time))
    x = np.repeat(v[:, None], n, axis=1)
    shown, curves, unsettled = [], [], []
    for j in idx:
        y = simulate_row(comp, comp.matrix.rows[j], x)
        end, before = y[:, -1], y[:, -1 - n // 10]
        scale = max(float(np.max(np.abs(end))), 1e-12)
        if not np.all(np.isfinite(end)) or float(np.max(np.abs(end - before))) > 1e-3 * scale:
            unsettled.append(j)
            continue
        shown.append(j)
        curves.append(end)
    torque = np.vstack(curves) if curves else np.empty((0, points))
    lugre_ss = None
    if lugre is not None:
        from edm_sym.engines.lugre import steady_state as lugre_steady_state

        lugre_ss = np.asarray(lugre_steady_state(lugre.result.params, v))
    return SteadyState(v, n * comp.sample_time, tuple(shown), torque, tuple(unsettled), lugre_ss)


def load_lugre_ref(path: str | Path) -> LuGreRef:
    """Load a LUGRE.json for the comparison.

    Parameters
    ----------
    path : path-like

    Returns
    -------
    LuGreRef
    """
    import hashlib

    from edm_sym.engines.lugre import load_lugre

    path = Path(path)
    res = load_lugre(path)
    return LuGreRef(res, path.name, hashlib.sha256(path.read_bytes()).hexdigest())
