"""The outcome of a LuGre identification, as held in memory and in LUGRE.json."""

from __future__ import annotations

import math
from dataclasses import dataclass

from edm_sym.lugre.model import LuGreParams

__all__ = ["LuGreProvenance", "LuGreResult"]


@dataclass(frozen=True)
class LuGreProvenance:
    """Where a LuGre result came from.

    Parameters
    ----------
    seed : int
        Random seed of the identification.
    package_version : str
        Version of edm_sym that produced the result.
    data_sha256 : str
        SHA-256 of the data file (64 lowercase hex digits).
    """

    seed: int
    package_version: str
    data_sha256: str


@dataclass(frozen=True)
class LuGreResult:
    """An identified LuGre model and how well it fits its data.

    Parameters
    ----------
    params : LuGreParams
        The identified parameters.
    method : str
        Identification method (``"scipy"``, ...).
    rmse : float
        Weighted fitness of eq. 8 on the identification data, >= 0.
    evaluations : int
        Number of model simulations the search used.
    sample_time : float
        Sample time of the data [s], > 0.
    target_name : str or None, optional
        Data column of the target torque (set when loaded from LUGRE.json).
    velocity_name : str or None, optional
        Data column of the velocity (set when loaded from LUGRE.json).
    provenance : LuGreProvenance or None, optional
        Seed, package version and data hash (set when loaded from LUGRE.json).

    Raises
    ------
    ValueError
        If a field has the wrong type or is out of range.
    """

    params: LuGreParams
    method: str
    rmse: float
    evaluations: int
    sample_time: float
    target_name: str | None = None
    velocity_name: str | None = None
    provenance: LuGreProvenance | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.params, LuGreParams):
            raise ValueError(f"params: expected LuGreParams, found {type(self.params).__name__}")
        if not isinstance(self.method, str) or not self.method:
            raise ValueError(f"method: expected a non-empty string, found {self.method!r}")
        rmse = float(self.rmse)
        if not (math.isfinite(rmse) and rmse >= 0.0):
            raise ValueError(f"rmse: expected a finite non-negative number, found {self.rmse!r}")
        object.__setattr__(self, "rmse", rmse)
        if isinstance(self.evaluations, bool) or int(self.evaluations) != self.evaluations:
            raise ValueError(f"evaluations: expected an integer, found {self.evaluations!r}")
        if self.evaluations < 0:
            raise ValueError(f"evaluations: expected >= 0, found {self.evaluations!r}")
        object.__setattr__(self, "evaluations", int(self.evaluations))
        ts = float(self.sample_time)
        if not (math.isfinite(ts) and ts > 0.0):
            raise ValueError(f"sample_time: expected a positive number, found {self.sample_time!r}")
        object.__setattr__(self, "sample_time", ts)
