"""Parsimony settings and the rules that choose a member of the front.

``[parsimony]`` in the config: ``prune`` (run the pruning pass, default
true), ``tolerance`` (default 0.01) and ``select``. The rules, applied to a
front sorted by complexity (see :mod:`edm_sym.engines.abstraction.prune`):

* ``best``: the lowest criterion;
* ``knee``: the largest drop of ln(criterion) per unit of complexity
  against the next simpler member, among members within 1.5 times the best
  criterion (PySR's choice of its "best" equation);
* ``simplest-within=PCT``: the simplest member whose criterion is within
  PCT % of the best, and of the search's own model when it is given
  (``reference``): moving parameters off their bounds before pruning may
  cost up to the tolerance already, and the two must not add up.

The default is ``simplest-within=`` the tolerance in percent (1 %).
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Protocol

from edm_sym.core.errors import ConfigError
from edm_sym.engines.abstraction.tables import settings_from_table

KNEE_WITHIN = 1.5
_KEYS = ("prune", "tolerance", "select", "criterion", "start", "refit", "tie", "law_rows")
#: What the criterion measures on the held-out part: the plain RMSE or eq. 8 with the
#: final step's weighting.
CRITERIA = ("rmse", "fitness")
#: Which model the pruning starts from: the step best with the lowest plain RMSE over the
#: whole abstraction log (the held-out RMSE choosing among those within ``tie``), or the
#: last step's best.
STARTS = ("best-step", "last-step")
_SELECT = re.compile(r"^(best|knee|simplest-within=(\d+(\.\d*)?|\.\d+)([eE][-+]?\d+)?)$")


class _Member(Protocol):
    complexity: int
    criterion: float


@dataclass(frozen=True)
class ParsimonySettings:
    """The ``[parsimony]`` table of the config.

    Parameters
    ----------
    prune : bool
        Run the pruning pass (False: export the search's model, no front).
    tolerance : float
        Relative worsening of the criterion a simplification may cost
        (default 0.01); the default selection is ``simplest-within=`` it.
    select : str or None
        ``"best"``, ``"knee"`` or ``"simplest-within=PCT"``; None: the
        simplest member within ``tolerance``.
    criterion : str
        ``"rmse"`` (default): the plain RMSE on the held-out part;
        ``"fitness"``: eq. 8 there with the final step's weighting.
    start : str
        ``"best-step"`` (default): prune the step best with the lowest plain
        RMSE over the whole abstraction log, or among those within ``tie``
        of it the one with the lowest held-out RMSE
        (:func:`~edm_sym.engines.abstraction.finish.start_candidate`);
        ``"last-step"``: the last step's best (the paper's model).
    refit : int
        With ``start = "best-step"``: before choosing, each step best's
        parameters are refitted by least squares on the whole training part
        (Lambda = 1), at most this many evaluations each (default 600; 0: no
        refit); the refitted and the original step bests are the candidates.
    tie : float
        With ``start = "best-step"``: candidates whose whole-log RMSE is
        within this share of the lowest are tied, and the held-out RMSE
        chooses among them (default 0.02; 0: the whole log alone).
    law_rows : bool
        Before pruning, offer the plain rows of the linear laws (viscous on a
        velocity input, inertia on an acceleration input) and keep each one
        that lowers the criterion by more than ``tolerance``
        (:func:`~edm_sym.engines.abstraction.prune.offer_law_rows`; default true).
    """

    prune: bool = True
    tolerance: float = 0.01
    select: str | None = None
    criterion: str = "rmse"
    start: str = "best-step"
    refit: int = 600
    tie: float = 0.02
    law_rows: bool = True

    @property
    def from_step_bests(self) -> bool:
        """Whether the search's model is chosen among the step bests (pruning, ``best-step``)."""
        return self.prune and self.start == "best-step"

    def __post_init__(self) -> None:
        for name in ("prune", "law_rows"):
            if not isinstance(getattr(self, name), bool):
                raise ConfigError(f"parsimony.{name}",
                                  f"expected true or false, found {getattr(self, name)!r}")
        t = self.tolerance
        if isinstance(t, bool) or not isinstance(t, int | float) or not (
                math.isfinite(t) and 0 <= t <= 1):
            raise ConfigError("parsimony.tolerance", f"expected a number in [0, 1], found {t!r}")
        object.__setattr__(self, "tolerance", float(t) + 0.0)  # -0.0 is 0
        t = self.tie
        if isinstance(t, bool) or not isinstance(t, int | float) or not (
                math.isfinite(t) and 0 <= t <= 1):
            raise ConfigError("parsimony.tie", f"expected a number in [0, 1], found {t!r}")
        object.__setattr__(self, "tie", float(t) + 0.0)
        if self.select is not None:
            check_select(self.select, "parsimony.select")
        if self.criterion not in CRITERIA:
            raise ConfigError("parsimony.criterion",
                              f"expected one of {', '.join(CRITERIA)}, found {self.criterion!r}")
        r = self.refit
        if isinstance(r, bool) or not isinstance(r, int) or r < 0:
            raise ConfigError("parsimony.refit", f"expected an integer >= 0, found {r!r}")
        if self.start not in STARTS:
            raise ConfigError("parsimony.start",
                              f"expected one of {', '.join(STARTS)}, found {self.start!r}")

    @property
    def selection(self) -> str:
        """The selection rule in force."""
        return self.select or f"simplest-within={100 * self.tolerance:g}"

    def to_json(self) -> dict[str, Any]:
        """The settings as a config table."""
        return {"prune": self.prune, "tolerance": self.tolerance, "select": self.selection,
                "criterion": self.criterion, "start": self.start, "refit": self.refit,
                "tie": self.tie, "law_rows": self.law_rows}


def check_select(text: Any, where: str) -> str:
    """Refuse a selection rule other than ``best``, ``knee``, ``simplest-within=PCT``."""
    if not isinstance(text, str) or not _SELECT.match(text):
        raise ConfigError(where, f"expected best, knee or simplest-within=PCT, found {text!r}")
    if text.startswith("simplest-within=") and not math.isfinite(float(text.partition("=")[2])):
        raise ConfigError(where, f"expected simplest-within=PCT with a finite PCT, found {text!r}")
    return text


def parse_parsimony(where: str, doc: Any) -> ParsimonySettings:
    """Read the ``[parsimony]`` table of a config.

    Parameters
    ----------
    where : str
        ``"<file>: parsimony"``, for messages.
    doc : mapping
        The parsed table.

    Returns
    -------
    ParsimonySettings

    Raises
    ------
    ConfigError
        Unknown key, wrong type or a value out of range.
    """
    return settings_from_table(ParsimonySettings, _KEYS, where, doc)


def select(front: Sequence[_Member], rule: str, reference: float | None = None) -> int:
    """Index of the front member chosen by ``rule`` (see the module docstring).

    ``reference``: the criterion of the search's model, before any change
    (``simplest-within`` stays within PCT % of it as well; when no member
    does, the best member is chosen).

    Raises
    ------
    ConfigError
        An unknown rule.
    """
    check_select(rule, "select")
    crit = [m.criterion for m in front]
    best = min(crit)
    if rule == "best":
        return crit.index(best)
    if rule == "knee":
        score = [0.0] + [
            -(math.log(max(crit[k], 1e-300)) - math.log(max(crit[k - 1], 1e-300)))
            / (front[k].complexity - front[k - 1].complexity) for k in range(1, len(front))]
        ok = [k for k in range(len(front)) if crit[k] <= KNEE_WITHIN * best]
        return max(ok, key=lambda k: (score[k], -k))
    pct = float(rule.split("=", 1)[1])
    base = best if reference is None or not math.isfinite(reference) else min(best, reference)
    return next((k for k in range(len(front)) if crit[k] <= base * (1 + pct / 100) + 1e-300),
                crit.index(best))
