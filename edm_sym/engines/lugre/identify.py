"""Identification of the LuGre model on a free-motion log (fitness: eq. 8).

Methods are looked up in :data:`METHODS` (name -> function); a new one (like
the project's genetic algorithm, ``"ga"`` in :mod:`edm_sym.engines.lugre.ga`)
registers itself with :func:`register_method` and receives a
:class:`LuGreProblem`. ``method="both"`` runs the methods of :data:`BOTH` and
returns the better result, with every method's score in its ``comparison``.

The ``"scipy"`` method uses variable projection: the friction torque is linear
in ``(tau_c, sigma1, sigma2)`` once the bristle trajectory is fixed, and that
trajectory depends only on four *shape* parameters,

* ``v_s`` (Stribeck velocity),
* ``r = tau_s / tau_c`` (stiction ratio),
* ``l = tau_c / sigma0`` (bristle deflection at high speed) and
* ``z0`` as a fraction of ``max(tau_c, tau_s) / sigma0``.

So the global search (:func:`scipy.optimize.differential_evolution`, seeded)
and the local refinement (bounded Nelder-Mead) run over those four, in log
space for the first three, and every evaluation solves a 3-column
non-negative weighted least-squares problem for the linear ones exactly.
"""

from __future__ import annotations

import inspect
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike
from scipy import linalg, optimize

from edm_sym.core.errors import ConfigError, DataFormatError
from edm_sym.core.fitness import fitness, magnitude_problem
from edm_sym.engines.lugre.model import (
    LuGreParams,
    _as_velocity,
    _check_ts,
    bristle_coefficients,
    bristle_trajectories,
    simulate_lugre,
    weighted_rmse,
)
from edm_sym.engines.lugre.result import LuGreResult, MethodScore

__all__ = [
    "BOTH",
    "METHODS",
    "IdentifyMethod",
    "LuGreProblem",
    "LuGreProgress",
    "MethodOutcome",
    "identify_lugre",
    "register_method",
    "search_space",
    "shape_bound_flags",
]


@dataclass(frozen=True, eq=False)
class LuGreProblem:
    """One identification task: fit the LuGre friction to ``target``.

    Parameters
    ----------
    target : numpy.ndarray
        Torque to reproduce per sample (finite, 1-D).
    velocity : numpy.ndarray
        Velocity per sample (finite, 1-D, same length, not all zero).
    ts : float
        Sample time [s].
    weights : numpy.ndarray
        Weighting function Lambda of eq. 8 per sample (>= 0, not all zero).
    deadline : float or None
        :func:`time.monotonic` value at which a method must stop and return
        its best parameters so far; None for no limit.
    progress : callable or None
        Called with a :class:`LuGreProgress` after every evaluation (the
        engine prints nothing; the caller renders and throttles it).
    method : str
        The method's name, for ``progress``.
    starts : tuple of int
        Where further logs begin in the series (several logs laid end to
        end, each simulated from rest); empty for one log.
    """

    target: np.ndarray
    velocity: np.ndarray
    ts: float
    weights: np.ndarray
    deadline: float | None = None
    progress: Callable[[LuGreProgress], None] | None = None
    method: str = ""
    start: float = field(default_factory=time.monotonic)
    starts: tuple[int, ...] = ()

    @property
    def torque_scale(self) -> float:
        """float: ``max |target|`` (1 when the target is all zero)."""
        scale = float(np.max(np.abs(self.target)))
        return scale if scale > 0.0 else 1.0

    @property
    def velocity_scale(self) -> float:
        """float: ``max |velocity|`` (> 0)."""
        return float(np.max(np.abs(self.velocity)))

    def fitness(self, params: LuGreParams) -> float:
        """Eq. 8 fitness of ``params`` on this problem's data.

        Parameters
        ----------
        params : LuGreParams
            Candidate parameters.

        Returns
        -------
        float
            Weighted RMS of ``target - simulate_lugre(params, velocity, ts)``.
        """
        return weighted_rmse(self.target, simulate_lugre(params, self.velocity, self.ts,
                                                         starts=self.starts), self.weights)

    def time_is_up(self) -> bool:
        """Whether the deadline has passed.

        Returns
        -------
        bool
            True once :func:`time.monotonic` reaches ``deadline``.
        """
        return self.deadline is not None and time.monotonic() >= self.deadline


@dataclass(frozen=True)
class LuGreProgress:
    """What an identification's ``progress`` callback is told after every evaluation.

    Attributes
    ----------
    method : str
        The method running (``"scipy"`` or ``"ga"``).
    generation : int
        Generations (iterations of the global search) done.
    evaluations : int
        Model simulations so far in this method.
    best : float
        Best fitness (eq. 8) so far.
    elapsed : float
        Seconds since the method started.
    budget : int or None
        Most evaluations the method runs without a time limit (None: the
        stopping rule decides).
    deadline_in : float or None
        Seconds to the time limit, or None.
    """

    method: str
    generation: int
    evaluations: int
    best: float
    elapsed: float
    budget: int | None = None
    deadline_in: float | None = None


#: Most evaluations of the ``"scipy"`` method: differential evolution (150
#: iterations after the initial population, 10 x 4 individuals each) and 800
#: Nelder-Mead steps.
SCIPY_BUDGET = 151 * 40 + 800


@dataclass(frozen=True)
class MethodOutcome:
    """What an identification method returns.

    Parameters
    ----------
    params : LuGreParams
        Best parameters found.
    evaluations : int
        Number of model simulations used.
    """

    params: LuGreParams
    evaluations: int


#: Signature of an identification method: ``fn(problem, *, seed) -> MethodOutcome``.
IdentifyMethod = Callable[..., MethodOutcome]

#: Registered identification methods, by name.
METHODS: dict[str, IdentifyMethod] = {}

#: The methods ``method="both"`` runs, in this order; the first wins a tie.
BOTH: tuple[str, ...] = ("scipy", "ga")


def register_method(name: str) -> Callable[[IdentifyMethod], IdentifyMethod]:
    """Register an identification method under ``name`` (decorator).

    Parameters
    ----------
    name : str
        Method name, as passed to :func:`identify_lugre`.

    Returns
    -------
    callable
        Decorator that stores the function in :data:`METHODS` and returns it.
        The function is called as ``fn(problem, seed=seed)`` with a
        :class:`LuGreProblem`, must be deterministic for a given seed, must
        return its best parameters once ``problem.time_is_up()``, and returns
        a :class:`MethodOutcome`.

    Raises
    ------
    ValueError
        If ``name`` is already registered.
    """

    def decorate(fn: IdentifyMethod) -> IdentifyMethod:
        if name in METHODS:
            raise ValueError(f"method {name!r} is already registered")
        METHODS[name] = fn
        return fn

    return decorate


def search_space(problem: LuGreProblem) -> dict[str, tuple[float, float, str]]:
    """A bounded search box for the seven parameters, derived from the data.

    Meant for direct searches (e.g. a genetic algorithm over the seven
    parameters); the ``"scipy"`` method searches its own reduced space.

    Parameters
    ----------
    problem : LuGreProblem
        The identification task.

    Returns
    -------
    dict of str to (float, float, str)
        ``name -> (low, high, scale)`` with scale ``"log"`` (search
        ``log10`` of the value) or ``"linear"``.
    """
    t_max, v_max = problem.torque_scale, problem.velocity_scale
    sigma0_low, sigma0_high = 1e2, 1e8
    # |z0| up to the largest steady deflection the box allows.
    z_max = 2.0 * t_max / sigma0_low
    return {
        "v_s": (1e-4 * v_max, v_max, "log"),
        "tau_c": (1e-6 * t_max, 2.0 * t_max, "log"),
        "tau_s": (1e-6 * t_max, 2.0 * t_max, "log"),
        "z0": (-z_max, z_max, "linear"),
        "sigma0": (sigma0_low, sigma0_high, "log"),
        "sigma1": (1e-6, 1e2, "log"),
        "sigma2": (0.0, t_max / v_max, "linear"),
    }


class _TimeUp(Exception):
    """Raised inside an objective to end a search at the deadline."""


class _VarPro:
    """Variable-projection objective over the four shape parameters.

    ``theta = (log10 v_s, log10 r, log10 l, zf)``; see the module docstring.
    Counts evaluations and keeps the best point seen.
    """

    def __init__(self, problem: LuGreProblem):
        self.problem = problem
        self.v = problem.velocity
        self.v2 = problem.velocity**2
        self.sw = np.sqrt(problem.weights)
        self.yw = problem.target * self.sw
        self.tau_c_min = 1e-9 * problem.torque_scale
        self.evaluations = 0
        self.generation = 0
        self.budget: int | None = None
        self.best_f = math.inf
        self.best: tuple[np.ndarray, np.ndarray] | None = None
        v_max, step = problem.velocity_scale, problem.velocity_scale * problem.ts
        self.bounds = [
            (math.log10(1e-4 * v_max), math.log10(v_max)),
            (-3.0, 2.0),
            (math.log10(1e-6 * step), math.log10(1e3 * step)),
            (-1.0, 1.0),
        ]

    def columns(self, theta: np.ndarray) -> np.ndarray:
        """Regressors of (tau_c, sigma1, sigma2) for shape ``theta``, shape (3, N)."""
        v_s, r, ell = 10.0 ** theta[0], 10.0 ** theta[1], 10.0 ** theta[2]
        g = ell * (1.0 + (r - 1.0) * np.exp(-self.v2 / (v_s * v_s)))
        z_ss, decay, rate = bristle_coefficients(g, self.v, self.problem.ts)
        e = bristle_trajectories(z_ss, decay, theta[3] * ell * max(r, 1.0), self.problem.starts)
        return np.stack([(z_ss + e) / ell, -rate * e, self.v])

    def solve(self, theta: np.ndarray) -> tuple[float, np.ndarray]:
        """Best non-negative (tau_c, sigma1, sigma2) for ``theta`` and its fitness."""
        cols = self.columns(theta)
        aw = cols * self.sw
        norms = np.sqrt(np.einsum("ij,ij->i", aw, aw))
        active = np.flatnonzero(norms > 1e-12 * norms.max())
        m = aw[active] / norms[active, None]
        gram = m @ m.T + 1e-12 * np.eye(len(active))
        chol = linalg.cholesky(gram)  # upper: gram = chol.T @ chol
        q = linalg.solve_triangular(chol, m @ self.yw, trans="T")
        # tau_c (column 0) keeps a small positive lower bound, so sigma0 = tau_c / l > 0.
        low = np.zeros(len(active))
        if active[0] == 0:
            low[0] = self.tau_c_min * norms[0]
        x, _ = optimize.nnls(chol, q - chol @ low)
        coef = np.zeros(3)
        coef[active] = (x + low) / norms[active]
        if coef[0] <= 0.0:
            coef[0] = self.tau_c_min
        resid = self.problem.target - coef @ cols
        return fitness(resid, self.problem.weights), coef

    def __call__(self, theta: np.ndarray) -> float:
        if self.best is not None and self.problem.time_is_up():
            raise _TimeUp
        theta = np.asarray(theta, dtype=float)
        f, coef = self.solve(theta)
        self.evaluations += 1
        if f < self.best_f:
            self.best_f, self.best = f, (theta.copy(), coef)
        report = self.problem.progress
        if report is not None:
            now = time.monotonic()
            deadline = self.problem.deadline
            report(LuGreProgress(self.problem.method, self.generation, self.evaluations,
                                 self.best_f, now - self.problem.start, self.budget,
                                 None if deadline is None else max(0.0, deadline - now)))
        return f

    def params(self, theta: np.ndarray, coef: np.ndarray) -> LuGreParams:
        """Convert a shape point and its linear coefficients to the seven parameters."""
        v_s, r, ell = 10.0 ** theta[0], 10.0 ** theta[1], 10.0 ** theta[2]
        tau_c, sigma1, sigma2 = (float(c) for c in coef)
        return LuGreParams(
            v_s=v_s,
            tau_c=tau_c,
            tau_s=r * tau_c,
            z0=float(theta[3]) * ell * max(r, 1.0),
            sigma0=tau_c / ell,
            sigma1=sigma1,
            sigma2=sigma2,
        )


#: The four shape parameters as the flags name them: (name, what it is).
SHAPE_NAMES = (("v_s", "Stribeck velocity"), ("tau_s/tau_c", "stiction ratio"),
               ("tau_c/sigma0", "bristle deflection"), ("z0 share", "initial bristle state"))


def shape_bound_flags(params: LuGreParams, velocity: ArrayLike, ts: float, *,
                      margin: float = 0.01) -> list[str]:
    """The identified shape parameters that sit on a bound of the search box.

    The methods search ``theta = (log10 v_s, log10 r, log10 l, zf)`` in a box
    derived from the data (:class:`_VarPro`); a value within ``margin`` (a
    share of the box's side) of a bound is a limit of the search, not an
    estimate, like an EDM parameter at its range bound.

    Parameters
    ----------
    params : LuGreParams
        The identified parameters.
    velocity : array_like
        The velocity of the log they were identified on (it sets the box).
    ts : float
        Its sample time [s].
    margin : float, default 0.01

    Returns
    -------
    list of str
        One line per parameter at a bound; empty when none is.
    """
    v = _as_velocity(velocity)
    problem = LuGreProblem(target=np.zeros(len(v)), velocity=v, ts=_check_ts(ts),
                           weights=np.ones(len(v)))
    bounds = _VarPro(problem).bounds
    ell = params.tau_c / params.sigma0 if params.sigma0 > 0 else math.nan
    r = params.tau_s / params.tau_c if params.tau_c > 0 else math.nan
    theta = (math.log10(params.v_s) if params.v_s > 0 else -math.inf,
             math.log10(r) if r > 0 else -math.inf,
             math.log10(ell) if ell > 0 else -math.inf,
             params.z0 / (ell * max(r, 1.0)) if ell > 0 else math.nan)
    out = []
    for k, ((lo, hi), value) in enumerate(zip(bounds, theta, strict=True)):
        if not math.isfinite(value) and not math.isinf(value):
            continue
        share = (value - lo) / (hi - lo)
        if margin < share < 1.0 - margin:
            continue
        side, bound = ("low", lo) if share <= margin else ("high", hi)
        name, meaning = SHAPE_NAMES[k]
        shown = (lambda x: f"{x:.4g}") if k == 3 else (lambda x: f"{10.0 ** x:.4g}")
        found = shown(value) if math.isfinite(value) else "0"
        out.append(f"LuGre {name} ({meaning}) = {found} is at its {side} bound "
                   f"{shown(bound)} of the search; its value is a limit of the search, "
                   "not an estimate")
    return out


def _seed_kwargs(seed: int) -> dict[str, object]:
    # scipy >= 1.15 takes ``rng``; older versions only ``seed``.
    if "rng" in inspect.signature(optimize.differential_evolution).parameters:
        return {"rng": np.random.default_rng(seed)}
    return {"seed": seed}


@register_method("scipy")
def _identify_scipy(problem: LuGreProblem, *, seed: int) -> MethodOutcome:
    """Differential evolution then Nelder-Mead over the shape parameters."""
    objective = _VarPro(problem)
    objective.budget = SCIPY_BUDGET

    def stop(*_args: object, **_kwargs: object) -> bool:
        objective.generation += 1
        return problem.time_is_up()

    try:
        optimize.differential_evolution(
            objective,
            objective.bounds,
            popsize=10,
            maxiter=150,
            tol=1e-4,
            atol=1e-6 * problem.torque_scale,
            mutation=(0.5, 1.0),
            recombination=0.7,
            polish=False,
            init="latinhypercube",
            callback=stop,
            workers=1,
            **_seed_kwargs(seed),
        )
        assert objective.best is not None
        optimize.minimize(
            objective,
            objective.best[0],
            method="Nelder-Mead",
            bounds=objective.bounds,
            options={
                "maxfev": 800,
                "xatol": 1e-5,
                "fatol": 1e-9 * problem.torque_scale,
                "adaptive": True,
            },
        )
    except _TimeUp:
        pass
    assert objective.best is not None
    return MethodOutcome(objective.params(*objective.best), objective.evaluations)


def _as_series(name: str, values: ArrayLike, n: int) -> np.ndarray:
    arr = np.asarray(values, dtype=float)
    if arr.shape != (n,):
        raise DataFormatError(name, f"expected a 1-D array of {n} samples, found shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        bad = int(np.flatnonzero(~np.isfinite(arr))[0])
        raise DataFormatError(f"{name}[{bad}]", f"expected a finite number, found {arr[bad]!r}")
    return arr


def identify_lugre(
    target: ArrayLike,
    velocity: ArrayLike,
    ts: float,
    *,
    method: str = "scipy",
    seed: int = 0,
    time_limit: float | None = None,
    weights: ArrayLike | None = None,
    progress: Callable[[LuGreProgress], None] | None = None,
    starts: Sequence[int] = (),
) -> LuGreResult:
    """Identify LuGre parameters that reproduce ``target`` from ``velocity``.

    Parameters
    ----------
    target : array_like
        Torque to reproduce per sample (the observer's free-motion estimate).
    velocity : array_like
        Velocity per sample, same length; not all zero.
    ts : float
        Sample time [s].
    method : str, optional
        Name of a registered method (see :data:`METHODS`), default
        ``"scipy"``; or ``"both"``: run each method of :data:`BOTH` and return
        the one with the lower fitness (the first on a tie), with every
        method's fitness and evaluations in ``comparison``.
    seed : int, optional
        Random seed; equal seeds give equal parameters (without a time limit).
    time_limit : float or None, optional
        Wall time in seconds after which the search stops and returns the
        best parameters found so far. With ``"both"``, method k of n stops at
        (k + 1) / n of it, so a method that ends early leaves its time to the
        next.
    weights : array_like or None, optional
        Weighting function Lambda of eq. 8 per sample (default all ones).
    progress : callable or None, optional
        Called with a :class:`LuGreProgress` after every evaluation; the
        engine prints nothing (``edm lugre`` renders it with
        :class:`edm_sym.application.progress.ProgressReporter`).
    starts : sequence of int, optional
        Several logs laid end to end: where each after the first begins
        (:func:`edm_sym.engines.abstraction.holdout.log_starts`). Each log is
        simulated from rest (the bristle state ``z0``) on its own, and the
        fitness is over all samples. Empty (the default) for one log.

    Returns
    -------
    LuGreResult
        Parameters, method, weighted fitness (eq. 8) on the data, number of
        evaluations and sample time (with ``"both"``: the better method's, and
        ``comparison`` set).

    Raises
    ------
    edm_sym.core.errors.ConfigError
        (a ValueError) If the method is unknown or an option is invalid.
    edm_sym.core.errors.DataFormatError
        (a ValueError) If a data series is malformed (length, NaN, all-zero
        velocity, negative weights).
    """
    if method not in METHODS and method != "both":
        known = ", ".join(sorted([*METHODS, "both"]))
        raise ConfigError("method", f"unknown method {method!r} (known: {known})")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ConfigError("seed", f"expected an integer >= 0, found {seed!r}")
    if time_limit is not None and not (
        isinstance(time_limit, (int, float, np.integer, np.floating))
        and not isinstance(time_limit, bool)
        and math.isfinite(float(time_limit))
        and time_limit >= 0
    ):
        raise ConfigError("time_limit", f"expected a non-negative number of seconds, found {time_limit!r}")
    v = _as_velocity(velocity)
    ts_f = _check_ts(ts)
    if len(v) <= len(LuGreParams.__dataclass_fields__):
        raise DataFormatError("velocity", f"expected more samples than the model's "
                              f"{len(LuGreParams.__dataclass_fields__)} parameters, found {len(v)}")
    if not np.any(v != 0.0):
        raise DataFormatError("velocity", "all samples are zero; the friction model cannot be identified")
    if np.all(v == v[0]):
        raise DataFormatError("velocity", f"expected a varying velocity (the friction curve needs "
                              f"several speeds), found {v[0]:g} on all {len(v)} samples")
    y = _as_series("target", target, len(v))
    for name, x in (("velocity", v), ("target", y)):
        problem = magnitude_problem(x)  # eq. 12 squares the velocity, eq. 8 the error
        if problem:
            raise DataFormatError(name, problem)
    cuts = tuple(int(k) for k in starts)
    if any(not a < b for a, b in zip((0, *cuts), (*cuts, len(v)), strict=True)):
        raise DataFormatError("starts", f"expected increasing sample indices between 0 and "
                              f"{len(v)}, found {list(starts)!r}")
    w = np.ones(len(v)) if weights is None else _as_series("weights", weights, len(v))
    if np.any(w < 0.0) or not np.any(w > 0.0):
        raise DataFormatError("weights", "expected non-negative values, not all zero")
    names = BOTH if method == "both" else (method,)
    start = time.monotonic()
    found: dict[str, tuple[LuGreParams, MethodScore]] = {}
    for k, name in enumerate(names):
        deadline = None if time_limit is None else start + float(time_limit) * (k + 1) / len(names)
        problem = LuGreProblem(target=y, velocity=v, ts=ts_f, weights=w, deadline=deadline,
                               progress=progress, method=name, starts=cuts)
        outcome = METHODS[name](problem, seed=int(seed))
        found[name] = (outcome.params, MethodScore(problem.fitness(outcome.params), outcome.evaluations))
    best = min(names, key=lambda name: found[name][1].fitness)  # min keeps the first on a tie
    params, score = found[best]
    return LuGreResult(
        params=params,
        method=best,
        rmse=score.fitness,
        evaluations=score.evaluations,
        sample_time=ts_f,
        comparison={name: found[name][1] for name in names} if method == "both" else None,
    )
