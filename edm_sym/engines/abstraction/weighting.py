"""The weighting function Lambda(q) of the fitness (paper, eq. 8), given as data.

A weighting is the product of up to three factors, each optional:

* ``constant`` -- one number for every sample;
* time windows (eq. 15) -- ``windows = [[t_start, t_end, weight], ...]``; a
  sample at time t gets the weight of the last window with
  ``t_start <= t < t_end`` and ``otherwise`` (default 0) outside every window;
* a threshold on the target (eq. 16) -- ``threshold``, ``above``, ``below``:
  ``above`` where ``|target| >= threshold``, ``below`` elsewhere.

Nothing here evaluates code: a weighting is numbers only.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from edm_sym.core.errors import ConfigError

WEIGHTING_KEYS = ("constant", "windows", "otherwise", "threshold", "above", "below")


@dataclass(frozen=True)
class Weighting:
    """Lambda(q) as data: constant x time windows x threshold on |target|.

    Parameters
    ----------
    constant : float
        Factor for every sample (>= 0).
    windows : tuple of (t_start, t_end, weight)
        Time windows [s], half open ``[t_start, t_end)``; later windows win
        where they overlap. Empty: no time factor.
    otherwise : float
        Time factor outside every window (only used with windows).
    threshold : float or None
        Threshold on ``|target|``; None: no threshold factor.
    above, below : float
        Factor where ``|target| >= threshold`` and where it is below.
    """

    constant: float = 1.0
    windows: tuple[tuple[float, float, float], ...] = ()
    otherwise: float = 0.0
    threshold: float | None = None
    above: float = 1.0
    below: float = 1.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "windows", tuple(tuple(map(float, w)) for w in self.windows))
        for name in ("constant", "otherwise", "above", "below"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise ValueError(f"{name}: expected a finite number >= 0, found {v}")
        for k, (t0, t1, w) in enumerate(self.windows):
            if not (math.isfinite(t0) and math.isfinite(t1) and t0 < t1):
                raise ValueError(f"windows[{k}]: expected t_start < t_end, found [{t0}, {t1}]")
            if not (math.isfinite(w) and w >= 0):
                raise ValueError(f"windows[{k}]: expected a weight >= 0, found {w}")
        if self.threshold is not None and not (math.isfinite(self.threshold)
                                               and self.threshold >= 0):
            raise ValueError(f"threshold: expected a finite number >= 0, found {self.threshold}")

    @property
    def is_constant(self) -> bool:
        """True when Lambda is the same for every sample."""
        return not self.windows and self.threshold is None

    def weights(self, t: np.ndarray, target: np.ndarray) -> np.ndarray | float:
        """Lambda(q) for every sample.

        Parameters
        ----------
        t : numpy.ndarray
            Sample times [s], shape (N,).
        target : numpy.ndarray
            The target column, shape (N,).

        Returns
        -------
        float or numpy.ndarray
            A float when the weighting is constant, else shape (N,).
        """
        if self.is_constant:
            return float(self.constant)
        lam = np.full(np.shape(target), float(self.constant))
        if self.windows:
            part = np.full(lam.shape, self.otherwise)
            for t0, t1, w in self.windows:
                part[(t >= t0) & (t < t1)] = w
            lam *= part
        if self.threshold is not None:
            lam *= np.where(np.abs(target) >= self.threshold, self.above, self.below)
        return lam

    def to_json(self) -> dict[str, Any]:
        """The JSON form (as in the config), recorded in each step of result.json."""
        out: dict[str, Any] = {"constant": self.constant}
        if self.windows:
            out["windows"] = [list(w) for w in self.windows]
            out["otherwise"] = self.otherwise
        if self.threshold is not None:
            out.update(threshold=self.threshold, above=self.above, below=self.below)
        return out


def _number(where: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ConfigError(where, f"expected a number, found {_show(value)}")
    if not math.isfinite(value):
        raise ConfigError(where, f"expected a finite number, found {value}")
    return float(value)


def _show(value: Any) -> str:
    text = repr(value)
    return f"{type(value).__name__} {text if len(text) <= 40 else text[:37] + '...'}"


#: The largest weight factor: eq. 8 squares the error times the product of the factors,
#: which must stay a finite number (the paper's largest is 20000).
MAX_WEIGHT = 1e12
_TOO_HEAVY = ("expected a weight <= 1e12 (eq. 8 multiplies the squared error by it, and the "
              "product of the factors must stay finite), found {:g}")


def parse_weighting(where: str, doc: Any) -> Weighting:
    """Build a :class:`Weighting` from its config form, refusing anything unknown.

    Parameters
    ----------
    where : str
        ``"file.toml: step[2].weighting"``, for messages.
    doc : number or table
        A number is a constant weighting; a table holds the keys
        ``constant``, ``windows``, ``otherwise``, ``threshold``, ``above``,
        ``below``.

    Returns
    -------
    Weighting

    Raises
    ------
    ConfigError
        Naming ``where`` and the key.
    """
    if isinstance(doc, int | float) and not isinstance(doc, bool):
        doc = {"constant": doc}
    if not isinstance(doc, Mapping):
        raise ConfigError(where, f"expected a number or a table, found {_show(doc)}")
    for key in doc:
        if key not in WEIGHTING_KEYS:
            raise ConfigError(f"{where}.{key}",
                              f"unknown key (known: {', '.join(WEIGHTING_KEYS)})")
    kw: dict[str, Any] = {}
    for key in ("constant", "otherwise", "threshold", "above", "below"):
        if key in doc:
            kw[key] = _number(f"{where}.{key}", doc[key])
            if kw[key] < 0:
                raise ConfigError(f"{where}.{key}", f"expected a number >= 0, found {kw[key]}")
            if key != "threshold" and kw[key] > MAX_WEIGHT:
                raise ConfigError(f"{where}.{key}", _TOO_HEAVY.format(kw[key]))
    if ("above" in doc or "below" in doc) and "threshold" not in doc:
        raise ConfigError(f"{where}.threshold", "expected a threshold with above/below, found none")
    if "windows" in doc:
        wins = doc["windows"]
        if not isinstance(wins, list):
            raise ConfigError(f"{where}.windows",
                              f"expected a list of [t_start, t_end, weight], found {_show(wins)}")
        out = []
        for k, w in enumerate(wins):
            ww = f"{where}.windows[{k}]"
            if not isinstance(w, list) or len(w) != 3:
                raise ConfigError(ww, f"expected [t_start, t_end, weight], found {_show(w)}")
            t0, t1, lam = (_number(ww, v) for v in w)
            if not t0 < t1:
                raise ConfigError(ww, f"expected t_start < t_end, found [{t0}, {t1}]")
            if lam < 0:
                raise ConfigError(ww, f"expected a weight >= 0, found {lam}")
            if lam > MAX_WEIGHT:
                raise ConfigError(ww, _TOO_HEAVY.format(lam))
            out.append((t0, t1, lam))
        kw["windows"] = tuple(out)
    elif "otherwise" in doc:
        raise ConfigError(f"{where}.otherwise", "expected windows with otherwise, found none")
    return Weighting(**kw)
