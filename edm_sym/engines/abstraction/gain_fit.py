"""Gain fit: a deterministic local search that sets each row's scale by least squares.

The output of a row is proportional to the parameter ``a`` of a gain-like
element (``gain``, ``power_gain``, ``sin_amp``, ``tan_amp``) when every element
after it is linear and homogeneous (gains, filters, delays): scaling ``a``
by c scales the row by c. Given an individual's row outputs (already
simulated and cached), the scales c_j that minimise eq. 8 solve a small
weighted least-squares problem. The gain fit writes ``a_j * c_j`` back into
the chromosome (or turns a ``through`` at such a place into a gain of c_j);
the new individual is then evaluated like any other, and replaces the old
one only when it is really better.

This is the parameter shift of Fig. 7a taken to its optimum along the few
directions where the optimum has a closed form. A row with the right shape
but a wrong scale survives at once, which makes structures (a sign with a
level, a viscous gain) much easier to find; it draws no random numbers.

The small least-squares problem is solved where the rows are, in the worker
that evaluated the individual (:func:`row_scales`), and that worker also
makes the candidate (:func:`gain_fit`) and evaluates it
(:mod:`~edm_sym.engines.abstraction.candidates`); the main process only
writes the genes of the candidates that are better into the population.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from edm_sym.core.elements import BY_NAME, REGISTRY, ParamRange
from edm_sym.engines.abstraction.ga import THROUGH, Population

#: Elements whose output is their parameter times a function of the input.
SCALABLE = frozenset(c for c, el in REGISTRY.items() if el.scales_output)
#: Elements with f(c x) = c f(x) for every real c (linear, no offset).
HOMOGENEOUS = frozenset(c for c, el in REGISTRY.items() if el.homogeneous)
GAIN = BY_NAME["gain"].code


def scale_position(codes: Sequence[int], gain_allowed: bool) -> tuple[int, bool] | None:
    """Where a row can be scaled: (element index, True if it is a ``through`` to replace).

    The last gain-like element with only homogeneous elements after it; else,
    when ``gain`` may be used, the last ``through`` with only homogeneous
    elements after it; else None.
    """
    through_at = None
    for i in range(len(codes) - 1, -1, -1):
        c = int(codes[i])
        if c in SCALABLE:
            return i, False
        if c == THROUGH and through_at is None and gain_allowed:
            through_at = i
        if c not in HOMOGENEOUS:
            break
    return (through_at, True) if through_at is not None else None


#: Lookup tables by element code (codes outside the registry: neither).
_SCALABLE = np.array([c in SCALABLE for c in range(max(REGISTRY) + 1)], dtype=bool)
_HOMOGENEOUS = np.array([c in HOMOGENEOUS for c in range(max(REGISTRY) + 1)], dtype=bool)


def scale_places(codes: np.ndarray, gain_allowed: bool) -> tuple[np.ndarray, np.ndarray]:
    """:func:`scale_position` of every row of a population at once.

    Parameters
    ----------
    codes : numpy.ndarray
        Shape (..., n) element codes.
    gain_allowed : bool
        Whether a ``through`` may become a ``gain``.

    Returns
    -------
    pos : numpy.ndarray
        Shape (...): the element index, -1 where the row cannot be scaled.
    through : numpy.ndarray
        Shape (...): True where it is a ``through`` to replace.
    """
    codes = np.asarray(codes)
    shape, n = codes.shape[:-1], codes.shape[-1]
    pos = np.full(shape, -1, dtype=np.int64)
    through_at = np.full(shape, -1, dtype=np.int64)
    done = np.zeros(shape, dtype=bool)
    for i in range(n - 1, -1, -1):
        c = codes[..., i]
        hit = ~done & _SCALABLE[c]
        pos[hit] = i
        done |= hit
        if gain_allowed:
            through_at[~done & (c == THROUGH) & (through_at < 0)] = i
        done |= ~_HOMOGENEOUS[c]
    through = (pos < 0) & (through_at >= 0)
    pos[through] = through_at[through]
    return pos, through


def row_scales(gram: np.ndarray, gy: np.ndarray, free: np.ndarray, fitness: float,
               n_samples: int) -> tuple[np.ndarray, float, float] | None:
    """The least-squares change of the free rows' scales (computed where the rows are).

    Parameters
    ----------
    gram, gy : numpy.ndarray
        ``G[i, j] = sum(Lambda r_i r_j)`` and ``gy[i] = sum(Lambda r_i target)``.
    free : numpy.ndarray
        Bool, shape (m,): the rows that can be scaled.
    fitness : float
        The individual's eq. 8 value.
    n_samples : int
        N (eq. 8 is a mean).

    Returns
    -------
    tuple or None
        ``(delta, promise, base)``: the scales are ``1 + delta`` (one per
        free row), ``promise`` the decrease of the weighted sum of squares
        they give, ``base`` that sum now; None when there is nothing to fit.
    """
    if not free.any() or not np.isfinite(fitness) or fitness == 0.0:
        return None
    if not (np.all(np.isfinite(gram)) and np.all(np.isfinite(gy))):
        return None
    # Residual e = y - sum(r): r_i' W e = r_i' W y - sum_j r_i' W r_j.
    g = (gy - gram.sum(axis=1))[free]
    delta = row_gains(gram[np.ix_(free, free)], g)
    assert delta is not None  # without a ridge there is always a (minimum-norm) solution
    return delta, float(g @ delta), float(fitness) ** 2 * n_samples


def row_gains(gram: np.ndarray, rhs: np.ndarray, *, ridge: float | None = None
              ) -> np.ndarray | None:
    """The row-gain least squares: the normal equations ``gram @ c = rhs`` solved.

    ``gram[i, j] = sum(Lambda r_i r_j)`` over the rows to scale and ``rhs[i] =
    sum(Lambda r_i e)`` with the part of the target they are to fit. The
    GA's gain fit (:func:`row_scales`: ``c`` a change of scale, around 0)
    takes the minimum-norm solution (``lstsq``, relative cutoff 1e-10), so
    rows that are collinear keep their scales; the refit of a pruned model
    (:mod:`~edm_sym.engines.abstraction.prune`: ``c`` the gains themselves)
    adds ``ridge * trace(gram)`` to the diagonal and solves.

    The caller checks that ``gram`` and ``rhs`` are finite.

    Returns
    -------
    numpy.ndarray or None
        ``c``; None when the ridged system is singular.
    """
    if ridge is None:
        return np.linalg.lstsq(gram, rhs, rcond=1e-10)[0]
    try:
        return np.linalg.solve(gram + ridge * np.trace(gram) * np.eye(len(rhs)), rhs)
    except np.linalg.LinAlgError:
        return None


def gain_fit(
    pop: Population,
    scales: Sequence[tuple[np.ndarray, float, float] | None],
    places: tuple[np.ndarray, np.ndarray],
    ranges: Mapping[str, ParamRange],
    *,
    tol: float = 1e-5,
) -> tuple[np.ndarray, Population]:
    """Candidates with least-squares row scales, for individuals that would gain from them.

    Parameters
    ----------
    pop : Population
        The individuals.
    scales : sequence
        Per individual :func:`row_scales` over its free rows (as
        ``Evaluator.evaluation(..., free=...).scales``); None: skip it.
    places : tuple of numpy.ndarray
        :func:`scale_places` of ``pop.codes``: where each row is scaled.
    ranges : mapping
        Parameter ranges (new values are clipped into them).
    tol : float
        Least relative decrease of the squared fitness the fit must promise.

    Returns
    -------
    idx : numpy.ndarray
        Indices into ``pop`` of the individuals that got a candidate.
    candidates : Population
        The candidates, in the order of ``idx``.
    """
    pos_all, through_all = places
    idx: list[int] = []
    out_in, out_codes, out_ps = [], [], []
    for k, entry in enumerate(scales):
        if entry is None:
            continue
        delta, promise, base = entry
        if not promise > tol * base:
            continue
        free = np.flatnonzero(pos_all[k] >= 0)
        codes, ps = pop.codes[k].copy(), pop.ps[k].copy()
        changed = False
        for i, j in enumerate(free.tolist()):
            d = float(delta[i])
            if abs(d) < 1e-9:
                continue
            c = 1.0 + d
            pos, is_through = int(pos_all[k, j]), bool(through_all[k, j])
            if is_through:
                codes[j, pos] = GAIN
                ps[j, pos] = ranges["gain"].encode(c)
                changed = changed or codes[j, pos] != pop.codes[k, j, pos] or (
                    ps[j, pos] != pop.ps[k, j, pos])
                continue
            rng = ranges[REGISTRY[int(codes[j, pos])].name]
            a = rng.decode(float(ps[j, pos])) * c
            if rng.scaling == "log" and not a > 0:
                continue
            ps[j, pos] = rng.encode(a)
            changed = changed or ps[j, pos] != pop.ps[k, j, pos]
        if not changed:
            continue
        idx.append(k)
        out_in.append(pop.inputs[k].copy())
        out_codes.append(codes)
        out_ps.append(ps)
    if not idx:
        p, m, n = pop.shape
        return np.zeros(0, dtype=np.intp), Population(
            np.zeros((0, m), np.int64), np.zeros((0, m, n), np.int64), np.zeros((0, m, n)))
    return np.array(idx, dtype=np.intp), Population(
        np.array(out_in), np.array(out_codes), np.array(out_ps))
