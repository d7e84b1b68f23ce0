"""The outcome of a LuGre identification, as held in memory and in LUGRE.json."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from edm_sym.engines.lugre.model import LuGreParams

__all__ = ["LuGreProvenance", "LuGreResult", "MethodScore"]


def _check_fitness(where: str, value: Any) -> float:
    fitness = float(value)
    if not (math.isfinite(fitness) and fitness >= 0.0):
        raise ValueError(f"{where}: expected a finite non-negative number, found {value!r}")
    return fitness


def _check_evaluations(where: str, value: Any) -> int:
    if isinstance(value, bool) or int(value) != value:
        raise ValueError(f"{where}: expected an integer, found {value!r}")
    if value < 0:
        raise ValueError(f"{where}: expected >= 0, found {value!r}")
    return int(value)


@dataclass(frozen=True)
class MethodScore:
    """How one identification method did, for :attr:`LuGreResult.comparison`.

    Parameters
    ----------
    fitness : float
        Weighted fitness of eq. 8 of the method's parameters on the data, >= 0.
    evaluations : int
        Number of model simulations the method used, >= 0.

    Raises
    ------
    ValueError
        If a field has the wrong type or is out of range.
    """

    fitness: float
    evaluations: int

    def __post_init__(self) -> None:
        object.__setattr__(self, "fitness", _check_fitness("fitness", self.fitness))
        object.__setattr__(self, "evaluations", _check_evaluations("evaluations", self.evaluations))


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
    comparison : mapping of str to MethodScore, or None, optional
        Every method that was run, when several were (``method="both"``):
        method name -> its fitness and evaluations, held sorted by name. The
        entry of ``method`` must repeat ``rmse`` and ``evaluations``. Not
        part of the hash.

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
    comparison: Mapping[str, MethodScore] | None = field(default=None, hash=False)

    def __post_init__(self) -> None:
        if not isinstance(self.params, LuGreParams):
            raise ValueError(f"params: expected LuGreParams, found {type(self.params).__name__}")
        if not isinstance(self.method, str) or not self.method:
            raise ValueError(f"method: expected a non-empty string, found {self.method!r}")
        object.__setattr__(self, "rmse", _check_fitness("rmse", self.rmse))
        object.__setattr__(self, "evaluations", _check_evaluations("evaluations", self.evaluations))
        if self.comparison is not None:
            object.__setattr__(self, "comparison", self._checked_comparison(self.comparison))
        ts = float(self.sample_time)
        if not (math.isfinite(ts) and ts > 0.0):
            raise ValueError(f"sample_time: expected a positive number, found {self.sample_time!r}")
        object.__setattr__(self, "sample_time", ts)

    def _checked_comparison(self, comparison: object) -> dict[str, MethodScore]:
        if not isinstance(comparison, Mapping) or not comparison:
            raise ValueError(f"comparison: expected a non-empty mapping, found {comparison!r}")
        for name, score in comparison.items():
            if not isinstance(name, str) or not name:
                raise ValueError(f"comparison: expected method names, found {name!r}")
            if not isinstance(score, MethodScore):
                raise ValueError(f"comparison.{name}: expected a MethodScore, found {type(score).__name__}")
        if self.method not in comparison:
            raise ValueError(
                f"comparison: expected an entry for the method {self.method!r}, "
                f"found only {', '.join(sorted(comparison))}"
            )
        own = comparison[self.method]
        if own.fitness != self.rmse:
            raise ValueError(
                f"comparison.{self.method}.fitness: expected the result's fitness "
                f"{self.rmse!r}, found {own.fitness!r}"
            )
        if own.evaluations != self.evaluations:
            raise ValueError(
                f"comparison.{self.method}.evaluations: expected the result's "
                f"evaluations {self.evaluations!r}, found {own.evaluations!r}"
            )
        return {name: comparison[name] for name in sorted(comparison)}
