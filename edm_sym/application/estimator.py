"""``EDMRegressor``: the EDM abstraction as a scikit-learn estimator (docs/estimator.md).

::

    from edm_sym.application.estimator import EDMRegressor      # or edm_sym.EDMRegressor
    est = EDMRegressor(sample_time=1e-3, config="examples/configs/friction_quick.toml", seed=1)
    est.fit(df[["omega", "alpha"]], df["tau_ext"])
    est.score(df_eval[["omega", "alpha"]], df_eval["tau_ext"])
    print(est.sympy())

The rows of ``X`` are consecutive samples of **one** log: the compensator has
memory (filters, delays, relays), so predictions depend on the order of the
samples and on where the series starts.

scikit-learn is an optional extra (``pip install 'edm_sym[sklearn]'``); only
this module imports it, and ``import edm_sym`` does not import this module.
"""

from __future__ import annotations

import inspect
import math
import os
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

try:
    from sklearn.base import BaseEstimator, RegressorMixin
    from sklearn.utils.validation import _get_feature_names, check_array, check_is_fitted, check_X_y
except ImportError as exc:  # pragma: no cover - exercised in a subprocess by the tests
    raise ImportError(
        "edm_sym.EDMRegressor needs scikit-learn, an optional extra: "
        "pip install 'edm_sym[sklearn]' (or pip install scikit-learn)"
    ) from exc

from edm_sym.core.data import DataLog
from edm_sym.core.errors import ConfigError
from edm_sym.core.units import AXES
from edm_sym.engines.abstraction import AbstractionConfig, Parallel, abstract, load_config
from edm_sym.engines.models import EdmModel
from edm_sym.engines.simulate import simulate

__all__ = ["EDMRegressor"]

#: ``DataLog.source`` of the log that :meth:`EDMRegressor.fit` builds.
FIT_SOURCE = "<EDMRegressor.fit>"


class EDMRegressor(RegressorMixin, BaseEstimator):
    """An EDM disturbance compensator found by the hierarchical genetic algorithm.

    ``fit(X, y)`` runs :func:`edm_sym.engines.abstraction.abstract` on the log whose
    columns are the features of ``X`` (the inputs a row may select) and ``y``
    (the target, e.g. the RTOB's external torque estimate). ``predict(X)`` is
    the compensation torque from the reference simulator
    (:func:`edm_sym.engines.simulate`). The rows of ``X`` are consecutive samples of
    one log, ``sample_time`` seconds apart: predictions depend on the sample
    order (filters, delays and relays have memory, starting at rest at the
    first row).

    Parameters follow the scikit-learn convention: stored as given, checked by
    :meth:`fit`.

    Parameters
    ----------
    sample_time : float
        The time between two rows of ``X`` [s]; required by :meth:`fit`.
    config : str, path-like or AbstractionConfig, optional
        The abstraction's schedule and GA settings: a TOML file
        (docs/abstraction.md#config-format) or a config object; None runs the
        default schedule (which can take minutes; set ``time_limit``).
    seed : int, default 0
        Seed of the genetic algorithm: equal seeds give equal results.
    time_limit : float, optional
        Wall-clock seconds for :meth:`fit`; the run ends at the next generation
        boundary and keeps the best so far.
    roles : mapping of str to str or None, optional
        Feature name -> physical role (``"velocity"``, ``"acceleration"``,
        ``"angle"``, ``"angle_wrapped"`` or None) for :meth:`sympy`,
        :meth:`latex` and :meth:`describe`, over the defaults by name
        (docs/symbolic.md#input-roles).
    target_name : str, default "tau_ext"
        The name the target gets in the result (``result_.target``, the
        exported code's ``TARGET``); must differ from every feature name.
    workers : int, default 1
        Processes of the abstraction (None: every usable core).
    searches : int or None, default None
        Independent searches of the schedule, side by side on ``workers``
        (None: the config's ``searches``, 1); the model is chosen among all
        of them (docs/abstraction.md#independent-searches).
    progress : bool, default False
        Show the abstraction's progress on stderr: a bar on a terminal, a
        line every few seconds elsewhere (a notebook's log, CI).
    axis : str, default "rotary"
        ``"rotary"`` (rad, N m) or ``"linear"`` (m, N): the SI units of the
        log (docs/data.md#units), recorded in ``result_.axis``; :meth:`describe`,
        :meth:`to_c`, :meth:`to_python` and :meth:`to_control` print its units.
    observer_bandwidth : float, optional
        The bandwidth ``g`` [rad/s] of the observer that estimated ``y``
        (``g/(s + g)``), as ``edm abstract --observer-bandwidth``: the static
        laws' block and the rows of linear laws are offered through its
        low-pass before pruning, it is recorded in ``result_.provenance`` and
        :meth:`describe` names the inertia with its lag taken out
        (docs/describe.md#inertia-held-by-the-filters).

    Attributes
    ----------
    result_ : EdmResult
        The abstraction's result (compensator, steps, provenance); save it with
        :func:`edm_sym.save_result`.
    n_features_in_ : int
        The number of features seen by :meth:`fit`.
    feature_names_in_ : numpy.ndarray of str (object dtype)
        The features' names: the DataFrame's column names, the ``feature_names``
        given to :meth:`fit`, else ``x0``, ``x1``, ... They are the
        compensator's input names.

    See Also
    --------
    edm_sym.engines.abstraction.abstract : the function :meth:`fit` calls.
    edm_sym.simulate : the function :meth:`predict` calls.

    Examples
    --------
    >>> est = EDMRegressor(sample_time=1e-3, config="friction_quick.toml")  # doctest: +SKIP
    >>> est.fit(df[["omega"]], df["tau_ext"]).score(df[["omega"]], df["tau_ext"])  # doctest: +SKIP
    0.998
    """

    def __init__(
        self,
        *,
        sample_time: float | None = None,
        config: str | os.PathLike[str] | AbstractionConfig | None = None,
        seed: int = 0,
        time_limit: float | None = None,
        roles: Mapping[str, str | None] | None = None,
        target_name: str = "tau_ext",
        workers: int | None = 1,
        searches: int | None = None,
        progress: bool = False,
        axis: str = "rotary",
        observer_bandwidth: float | None = None,
    ) -> None:
        self.sample_time = sample_time
        self.config = config
        self.seed = seed
        self.time_limit = time_limit
        self.roles = roles
        self.target_name = target_name
        self.workers = workers
        self.searches = searches
        self.progress = progress
        self.axis = axis
        self.observer_bandwidth = observer_bandwidth

    # --- fitting and prediction ---

    def fit(self, X: Any, y: Any, *, feature_names: Sequence[str] | None = None,
            groups: Any = None) -> EDMRegressor:
        """Find the compensator of ``y`` from the features of ``X``.

        Parameters
        ----------
        X : pandas.DataFrame or array-like of shape (n_samples, n_features)
            The inputs, one row per sample, in time order.
        y : array-like of shape (n_samples,)
            The target (e.g. the RTOB's external torque estimate), in the
            axis's force unit (N m rotary, N linear).
        feature_names : sequence of str, optional
            Names of the features when ``X`` has none (a plain array); with a
            DataFrame they must equal its column names.
        groups : array-like of shape (n_samples,), optional
            Which log each sample belongs to: several logs (runs) in one
            ``X``, each a contiguous run of one label. Each is simulated from
            rest on its own and eq. 8 is taken over all of them
            (docs/abstraction.md#several-logs). ``X`` and ``y`` may also be
            lists of the logs' frames and targets.

        Returns
        -------
        EDMRegressor
            ``self``, fitted.

        Raises
        ------
        ValueError
            Missing or bad ``sample_time``, an unknown ``axis``, bad data (NaN,
            infinity, fewer than 2 samples, ``y`` of another length), names
            that are not unique or equal ``target_name``.
        ConfigError
            A bad ``config``, ``seed``, ``workers``, ``searches``, ``time_limit``, ``target_name``,
            ``roles`` or ``observer_bandwidth`` (a subclass of ValueError).
        DataFormatError
            A constant ``y``: nothing to model (a subclass of ValueError).
        """
        ts = self._checked_sample_time()
        axis = self._checked_axis()
        if not isinstance(self.target_name, str) or not self.target_name:
            raise ConfigError("EDMRegressor.target_name", f"expected a column name, found "
                              f"{self.target_name!r}")
        if self.roles is not None and (not isinstance(self.roles, Mapping) or not all(
                isinstance(k, str) and (v is None or isinstance(v, str))
                for k, v in self.roles.items())):
            raise ConfigError("EDMRegressor.roles", f"expected a mapping of feature names to "
                              f"roles (str or None), found {self.roles!r}")
        g = self.observer_bandwidth
        if g is not None and (isinstance(g, bool) or not isinstance(g, int | float | np.number)
                              or not (math.isfinite(float(g)) and float(g) > 0)):
            raise ConfigError("EDMRegressor.observer_bandwidth", f"expected a finite number > 0 "
                              f"[rad/s] or None, found {g!r}")
        if _is_list_of_frames(X):
            if not isinstance(y, list | tuple) or len(y) != len(X):
                raise ValueError(f"EDMRegressor.fit: y: expected a list of {len(X)} targets (one per "
                                 f"frame of X), found {type(y).__name__}")
            groups = np.concatenate([np.full(len(f), k) for k, f in enumerate(X)])
            if hasattr(X[0], "columns"):  # DataFrames: their names stay
                import pandas as pd

                X = pd.concat(list(X), ignore_index=True)
            else:
                X = np.concatenate([np.asarray(f, dtype=float) for f in X])
            y = np.concatenate([np.asarray(v, dtype=float).reshape(-1) for v in y])
        names = _names_of(X, feature_names)
        X, y = check_X_y(X, y, dtype=np.float64, ensure_min_samples=2, y_numeric=True)
        spans = _group_spans(groups, len(y))
        names = names if names is not None else [f"x{j}" for j in range(X.shape[1])]
        if len(names) != X.shape[1]:
            raise ValueError(f"EDMRegressor.fit: feature_names: expected {X.shape[1]} names (one per "
                             f"column of X), found {len(names)}")
        if len(set(names)) != len(names):
            dup = sorted({n for n in names if names.count(n) > 1})
            raise ValueError(f"EDMRegressor.fit: feature names: expected each name once, found {dup} "
                             "more than once")
        if self.target_name in names:
            raise ValueError(f"EDMRegressor.fit: target_name: {self.target_name!r} is also a feature "
                             "name; hint: EDMRegressor(target_name=...) with another name")
        columns = {name: np.array(X[:, j], dtype=np.float64) for j, name in enumerate(names)}
        columns[self.target_name] = np.array(y, dtype=np.float64)
        data = DataLog(columns, ts, source=FIT_SOURCE,
                       scalars={} if g is None else {"observer_bandwidth": float(g)})
        if len(spans) > 1:
            data = [data.window(a, b) for a, b in spans]
        from edm_sym.application.progress import ProgressReporter

        with ProgressReporter("EDMRegressor.fit", quiet=not self.progress) as reporter:
            result = abstract(data, target=self.target_name, inputs=names,
                              config=self._config(), seed=self.seed, time_limit=self.time_limit,
                              callback=reporter.abstraction, axis=axis, searches=self.searches,
                              parallel=Parallel(workers=self.workers))
        from edm_sym.application.summary import with_physics

        if g is not None:  # recorded as edm abstract --observer-bandwidth records it
            result = replace(result, provenance={**result.provenance, "observer_bandwidth": float(g)})
        self.result_ = with_physics(result, data)[0]
        self.n_features_in_ = X.shape[1]
        self.feature_names_in_ = np.asarray(names, dtype=object)
        return self

    def predict(self, X: Any, groups: Any = None) -> np.ndarray:
        """The compensation torque over ``X``, a time series, from the reference simulator.

        The compensator starts at rest at the first row and advances one sample
        per row, so the result depends on the order of the rows: predict a
        whole log at once, not shuffled rows or separate batches.

        Parameters
        ----------
        X : pandas.DataFrame or array-like of shape (n_samples, n_features)
            The features of :meth:`fit`, in the same order (a DataFrame's
            column names must equal ``feature_names_in_``).
        groups : array-like of shape (n_samples,), optional
            Which log each sample belongs to (as for :meth:`fit`): each log
            is simulated from rest on its own.

        Returns
        -------
        numpy.ndarray of shape (n_samples,)
            ``edm_sym.engines.simulate(result_, X).total``, in the axis's force
            unit (N m or N).

        Warns
        -----
        UserWarning
            Where a row reads a feature beyond the range it had in :meth:`fit`
            (docs/estimator.md#predict-warns-where-the-model-extrapolates): the row extrapolates there.
        """
        check_is_fitted(self, "result_")
        arr = check_array(X, dtype=np.float64)
        spans = _group_spans(groups, len(arr))
        columns = self._columns(arr, X)
        for line in EdmModel(self.result_).beyond_ranges(
                DataLog(columns, self.result_.sample_time, source="X")):
            warnings.warn(f"EDMRegressor.predict: {line}", UserWarning, stacklevel=2)
        if len(spans) > 1:
            return np.concatenate([simulate(self.result_, {k: v[a:b] for k, v in columns.items()}
                                            ).total for a, b in spans])
        return simulate(self.result_, columns).total

    # --- the fitted model in other forms ---

    def sympy(self) -> Any:
        """The compensator as one sympy expression: the sum of its simplified rows.

        Returns
        -------
        sympy.Expr
            ``edm_sym.decode(result_, roles=roles).total()`` (numbers, no ``a_k``
            symbols); the features are its symbols.
        """
        return self._model().total(numeric=True, simplified=True)

    def latex(self) -> str:
        """The compensator's sum expression as LaTeX (math mode, no delimiters).

        Returns
        -------
        str
        """
        from edm_sym.outputs.printing.latex import latex  # the one place that writes LaTeX

        return latex(self.sympy())

    def describe(self, X: Any = None, y: Any = None, **options: Any) -> Any:
        """What the compensator found, row by row, by ``edm_sym.describe``.

        Parameters
        ----------
        X, y : optional
            A log (features as for :meth:`predict`, and its target) to measure
            each row's contribution on; without them ``edm_sym.describe`` uses
            what the result records (nothing, for a result of :meth:`fit`).
        **options
            Passed to ``edm_sym.describe``; ``roles`` is this estimator's
            unless given.

        Returns
        -------
        Any
            What ``edm_sym.describe`` returns (a ``Description``: ``.table()``,
            ``.to_json()``).

        Raises
        ------
        NotImplementedError
            When the installed edm_sym has no ``describe``.
        """
        import edm_sym

        check_is_fitted(self, "result_")
        describe = getattr(edm_sym, "describe", None)
        if describe is None:
            raise NotImplementedError(
                "EDMRegressor.describe: this version of edm_sym has no edm_sym.describe; "
                "use .sympy() or edm_sym.decode(est.result_) and its rows' terms instead")
        if _accepts(describe, "roles") and self.roles is not None:
            options.setdefault("roles", self.roles)
        if X is not None or y is not None:
            if X is None or y is None:
                raise ValueError("EDMRegressor.describe: expected both X and y (a log to measure the "
                                 "rows on) or neither, found only one")
            options["data"] = self._log(X, y, source="<EDMRegressor.describe>")
        return describe(self.result_, **options)

    def to_c(self, out_dir: str | os.PathLike[str], **options: Any) -> list[Path]:
        """Write the compensator as C (``<prefix>.h``, ``<prefix>.c``) into ``out_dir``.

        Parameters
        ----------
        out_dir : path-like
            The output folder; created when missing.
        **options
            ``prefix``, ``real`` (see :func:`edm_sym.export`).

        Returns
        -------
        list of pathlib.Path
            The files written.
        """
        from edm_sym import export

        check_is_fitted(self, "result_")
        return export(self.result_, "c", out_dir, **options)

    def to_python(self, out_dir: str | os.PathLike[str], **options: Any) -> list[Path]:
        """Write the compensator as a standalone Python module (``<prefix>.py``) into ``out_dir``.

        Parameters
        ----------
        out_dir : path-like
            The output folder; created when missing.
        **options
            ``prefix`` (see :func:`edm_sym.export`).

        Returns
        -------
        list of pathlib.Path
            The files written.
        """
        from edm_sym import export

        check_is_fitted(self, "result_")
        return export(self.result_, "python", out_dir, **options)

    def to_control(self, **options: Any) -> Any:
        """The fitted compensator as a discrete python-control system (``dt = Ts``).

        Parameters
        ----------
        **options
            ``output`` (default ``"tau_cmp"``) and ``name``, as for
            :meth:`edm_sym.engines.symbolic.model.SymbolicModel.to_control`.

        Returns
        -------
        control.NonlinearIOSystem
            Inputs named as the features of :meth:`fit`, one output; its
            :func:`control.input_output_response` equals :meth:`predict`.
        """
        from edm_sym.engines.symbolic.model import build_model

        check_is_fitted(self, "result_")
        # The stages suffice: no simplification, no classification.
        comp = self.result_.compensator
        return build_model(comp, target=self.result_.target,
                           axis=self.result_.axis).to_control(**options)

    # --- helpers ---

    def _checked_sample_time(self) -> float:
        ts = self.sample_time
        ok = isinstance(ts, int | float | np.integer | np.floating) and not isinstance(ts, bool)
        if not ok or not math.isfinite(ts) or ts <= 0:
            raise ValueError(
                "EDMRegressor.fit: sample_time: expected the time between two rows of X in seconds "
                f"(a number > 0), found {ts!r}; hint: EDMRegressor(sample_time=1e-3)")
        return float(ts)

    def _checked_axis(self) -> str:
        if not (isinstance(self.axis, str) and self.axis in AXES):
            raise ValueError(
                f"EDMRegressor.fit: axis: expected {' or '.join(map(repr, AXES))}, found "
                f"{self.axis!r}; hint: EDMRegressor(axis='linear') for a log in m, m/s and N")
        return self.axis

    def _config(self) -> AbstractionConfig | None:
        cfg = self.config
        if cfg is None or isinstance(cfg, AbstractionConfig):
            return cfg
        if isinstance(cfg, str | os.PathLike):
            return load_config(cfg)
        raise ConfigError("EDMRegressor.config", "expected a TOML file name, an AbstractionConfig or "
                          f"None, found {type(cfg).__name__}")

    def _columns(self, checked: np.ndarray, X: Any) -> dict[str, np.ndarray]:
        """The features of fit by name, from ``checked`` (``X`` as a float array) and ``X``'s names."""
        names = _get_feature_names(X)
        want = list(self.feature_names_in_)
        if names is not None and list(names) != want:
            raise ValueError(f"EDMRegressor: X's columns: expected {want} (the features of fit, "
                             f"in that order), found {list(names)}")
        if checked.shape[1] != self.n_features_in_:
            raise ValueError(f"X has {checked.shape[1]} features, but {type(self).__name__} is expecting "
                             f"{self.n_features_in_} features as input.")
        return {name: checked[:, j] for j, name in enumerate(want)}

    def _log(self, X: Any, y: Any, *, source: str) -> DataLog:
        """``X`` (the features of fit) and ``y`` (the target) as a log at the result's sample time."""
        checked, y = check_X_y(X, y, dtype=np.float64, y_numeric=True)
        columns = self._columns(checked, X)
        columns[self.result_.target] = y
        return DataLog(columns, self.result_.sample_time, source=source)

    def _model(self) -> Any:
        """The decoded model of ``result_`` (decoded once per result and roles)."""
        from edm_sym import decode

        check_is_fitted(self, "result_")
        cached = getattr(self, "_decoded", None)
        if cached is not None and cached[0] is self.result_ and cached[1] == self.roles:
            return cached[2]
        model = decode(self.result_, roles=self.roles, systems=False)
        self._decoded = (self.result_, self.roles, model)
        return model


def _accepts(func: Any, name: str) -> bool:
    """True when ``func`` takes a keyword argument ``name`` (by name or through ``**kwargs``)."""
    try:
        params = inspect.signature(func).parameters.values()
    except (TypeError, ValueError):
        return False
    return any(p.name == name or p.kind is inspect.Parameter.VAR_KEYWORD for p in params)


def _names_of(X: Any, given: Sequence[str] | None) -> list[str] | None:
    """The feature names: a DataFrame's string columns, else ``given``, else None."""
    names = _get_feature_names(X)
    if given is not None:
        given = [str(n) for n in given]
        if names is not None and list(names) != given:
            raise ValueError(f"EDMRegressor.fit: feature_names: expected X's column names {list(names)} "
                             f"(or no feature_names), found {given}")
        return given
    return None if names is None else [str(n) for n in names]



def _is_list_of_frames(X: Any) -> bool:
    """A list of 2-D frames or arrays (several logs), not a list of rows."""
    return (isinstance(X, list | tuple) and len(X) > 0
            and all(len(getattr(f, "shape", ())) == 2 for f in X))


def _group_spans(groups: Any, n: int) -> list[tuple[int, int]]:
    """The ``(start, stop)`` of each log that ``groups`` labels (one span without groups).

    Raises
    ------
    ValueError
        Labels of another length, or a label in two places (a log is one run of samples).
    """
    if groups is None:
        return [(0, n)]
    g = np.asarray(groups)
    if g.shape != (n,):
        raise ValueError(f"EDMRegressor: groups: expected one label per sample ({n}), found shape "
                         f"{g.shape}")
    cuts = [0, *(np.flatnonzero(g[1:] != g[:-1]) + 1).tolist(), n]
    spans = list(zip(cuts[:-1], cuts[1:], strict=True))
    labels = [g[a] for a, _ in spans]
    seen = set()
    for (a, _), label in zip(spans, labels, strict=True):
        if label in seen:
            raise ValueError(f"EDMRegressor: groups: expected each log as one run of samples, found "
                             f"the label {label!r} again at sample {a}")
        seen.add(label)
    return [(int(a), int(b)) for a, b in spans]
